"""Three routes from a jointed model to amplitude-dependent modal data, as measured data.

Each route gives one entry per level (:class:`ident.modal_data.MeasuredData`, SI units:
``excitation`` in N, ``response_amplitude`` the drive-point displacement amplitude at
resonance in m) for the estimator (:mod:`inverse.estimate`):

* ``force`` (the paper's protocol): force-controlled stepped sine at the case's force
  levels, each level identified by LSCF (:func:`ident.levels.identify_levels`, the
  case study's options); ``control = force``, ``response_amplitude`` read at the
  identified resonance.
* ``response``: response-controlled stepped sine (:mod:`runs.response_control`) holding
  the drive-point amplitudes the force route reached at resonance, identified the same
  way; ``control = response``, ``excitation`` the line force at the identified
  resonance.
* ``epmc``: the nonlinear mode (:mod:`fe.epmc`) normalized at the drive point, read at
  the same amplitudes; ``omega2 = w^2``, ``zeta = xi/(2 w)``, ``excitation`` the force
  at resonance of eq. 1 of :mod:`fe.backbone`; ``control = response``.

All three run on one joint path (``exact``: continuous Iwan joints, first harmonic;
``bank``: Jenkins banks, the case's harmonics). Each route also returns per level the
joint slip amplitudes at resonance (n_levels, n_joints).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from casefile.jointed import NonlinearCase
from fe.epmc import epmc_backbone
from ident.levels import identify_levels, spline_at
from ident.modal_data import MeasuredData
from runs.campaign import Campaign, HBProtocol
from runs.response_control import ResponseControlProtocol, line_forces

__all__ = ["force_route", "response_route", "epmc_route", "linear_resonance_amplitude"]


def _physical_load(case: NonlinearCase) -> np.ndarray:
    load = np.zeros(case.model.basis.shape[0])
    load[case.drive_dof] = 1.0
    return load


def _target_hz(case: NonlinearCase) -> float:
    from fe.epmc import linear_mode

    return linear_mode(case.model, case.mode)[0] / (2 * np.pi)


def _levels(n) -> np.ndarray:
    return np.arange(1, n + 1)


def _run(case, campaign, progress, store=None, executor=None):
    """:func:`runs.stepped_sine.run_campaign`, stored in ``store/campaign-<protocol>-<hash12>``."""
    from runs.stepped_sine import campaign_hash, run_campaign

    if store is not None:
        h = campaign_hash(case.model, case.bank, campaign)[:12]
        store = Path(store) / f"campaign-{campaign.protocol.name}-{h}"
    return run_campaign(case.model, case.bank, campaign, store=store, progress=progress,
                        executor=executor)


def linear_resonance_amplitude(case: NonlinearCase, force=None) -> np.ndarray:
    """Drive-point displacement amplitudes (m) of the stuck-joint structure driven at its
    mode's frequency by ``force`` (N; default the case's levels)."""
    from fe.epmc import linear_mode

    F = case.force if force is None else np.asarray(force, dtype=float)
    w, m = linear_mode(case.model, case.mode)[0], case.model
    x = np.linalg.solve(m.K - w * w * m.M + 1j * w * m.C, case.load())
    return F * abs(case.load() @ x)


def _force_campaign_exact(case, campaign, progress):
    """Force-controlled levels on the exact path (:func:`fe.hb_exact.continuation_exact`):
    receptance (L, lines, outputs) and slip amplitudes (L, lines, joints)."""
    from fe.hb_exact import continuation_exact

    load = case.model.load(campaign.load)
    omegas = 2 * np.pi * campaign.frequency_hz
    rec, amp = [], []
    for F in campaign.force:
        sols = continuation_exact(case.model, case.joints, load * F, omegas)
        rec.append([s.first_harmonic(case.model)[campaign.outputs] / F for s in sols])
        amp.append([s.slip_amplitude for s in sols])
    return np.array(rec), np.array(amp)


def _identified(case, rec, amp, force):
    """LSCF per level on the response DOF (column 1), amplitudes at resonance."""
    n_j = case.model.n_joints
    ident = identify_levels(case.lines_hz, rec[:, :, 1], amp, force, case.band_hz,
                            _target_hz(case), np.ones(n_j), options=case.identify_options)
    if not np.all(np.isfinite(ident.omega2)):
        raise RuntimeError(f"{case.name}: the mode was not identified at every level")
    return ident


def force_route(case: NonlinearCase, path: str = "exact", force=None, progress=False):
    """The paper's protocol (module docstring). Returns ``(MeasuredData, slip)``."""
    F = case.force if force is None else np.asarray(force, dtype=float)
    outputs = np.array([case.drive_dof, case.response_dof])
    camp = Campaign(case.lines_hz, F, _physical_load(case), outputs, HBProtocol())
    if path == "exact":
        rec, amp = _force_campaign_exact(case, camp, progress)
    else:
        res = _run(case, camp, progress)
        rec, amp = res.receptance, res.slip_amplitude
    ident = _identified(case, rec, amp, F)
    drive = np.array([spline_at(case.lines_hz, np.abs(rec[lv, :, 0]), ident.frequency_hz[lv])
                      for lv in range(F.size)]) * F
    data = MeasuredData(level=_levels(F.size), excitation=F, omega2=ident.omega2,
                        zeta=ident.zeta, mode=None, run_order=None, response_amplitude=drive,
                        source=f"{case.name}: force-controlled stepped sine ({path})")
    return data, ident.slip


def response_route(case: NonlinearCase, held, path: str = "exact", progress=False,
                   store=None, executor=None):
    """Response control at the held drive-point amplitudes ``held`` (m); the campaign
    stored under ``store`` (resumable) and run on ``executor``
    (:func:`runs.stepped_sine.run_campaign`). Returns ``(MeasuredData, slip)``."""
    held = np.asarray(held, dtype=float)
    proto = (ResponseControlProtocol.exact(case.drive_dof, case.joints) if path == "exact"
             else ResponseControlProtocol(case.drive_dof, "bank", HBProtocol().settings))
    outputs = np.array([case.drive_dof, case.response_dof])
    camp = Campaign(case.lines_hz, held, _physical_load(case), outputs, proto)
    res = _run(case, camp, progress, store, executor)
    forces = line_forces(res, camp)
    ident = _identified(case, res.receptance, res.slip_amplitude, np.ones(held.size))
    F_res = np.array([spline_at(case.lines_hz, forces[lv], ident.frequency_hz[lv])
                      for lv in range(held.size)])
    data = MeasuredData(level=_levels(held.size), excitation=F_res, omega2=ident.omega2,
                        zeta=ident.zeta, mode=None, run_order=None, response_amplitude=held,
                        control=np.full(held.size, "response"),
                        source=f"{case.name}: response-controlled stepped sine ({path})")
    return data, ident.slip


def epmc_route(case: NonlinearCase, held, path: str = "exact"):
    """The EPMC backbone at the drive-point amplitudes ``held`` (m). Returns
    ``(MeasuredData, slip, Backbone)``."""
    held = np.asarray(held, dtype=float)
    bb = epmc_backbone(case.model, case.joint_harmonics(path), case.mode, held,
                       at=case.drive_dof)
    data = MeasuredData(level=_levels(held.size),
                        excitation=bb.force_at_resonance(case.drive_dof), omega2=bb.omega2,
                        zeta=bb.zeta, mode=None, run_order=None, response_amplitude=held,
                        control=np.full(held.size, "response"),
                        source=f"{case.name}: EPMC backbone ({path})")
    return data, bb.slip_amplitude, bb
