"""A measured-data table for a case file made by another route than the FE-levels fit
(:mod:`feloop.case_levels`), with a seeded ``chi`` the fit never sees.

Route: the case file's jointed model (:func:`casefile.nonlinear.nonlinear_case`,
Ritz basis, the file's ``[damping] zeta``) with its joints as Jenkins banks (8 sliders
per octave, :meth:`fe.reduction.JointBank.log_spaced`), not the exact Iwan describing
function; a stepped sine over ``LINES`` lines around the mode solved by multi-harmonic
balance (harmonics 1, 3, 5; 64 AFT samples, :func:`runs.stepped_sine.run_campaign`), not
phase resonance; each level's receptance identified by LSCF
(:func:`ident.identify.identify_modes`, the mode with the largest residue); Gaussian
repeatability noise (relative sd ``SIGMA_OMEGA2`` of omega^2, ``SIGMA_ZETA`` of zeta)
from the seed. The joints keep the file's ``kt``, ``fs``, ``beta`` and take the seeded
``chi`` (uniform in ``CHI_RANGE``); the forces (N, 10 levels over a factor 512) put the
top level's linear slip at ``TOP_SLIP`` phi_max (micro-slip only: the hidden effect is
``none``).

Another law (:mod:`casefile.laws`) keeps every parameter the file gives (the seed draws
the noise only) and its top level's linear slip is ``TOP_SLIP_OTHER`` slip scales (a
Jenkins slider is linear below its slip): ``jenkins`` runs the same multi-harmonic
stepped sine on its own bank (one slider per joint element); ``bouc-wen``, which has no
AFT march, is solved line by line by first-harmonic balance with its describing
function (:func:`fe.hb_exact.continuation_exact`); both identified by LSCF as above.

``python -m cases.stepped_sine_test CASE.toml OUT.csv SEED [MODES] [--top-slip X]``
writes the table (``x_source = simulated``; the seeded chi only printed) and prints the
truth; ``MODES`` (e.g. ``1,2``): those bending modes of one joint (one seeded chi), one
table, each with the noise of seed ``SEED + 100 mode``. SI units.
"""
from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np

from fe.harmonic_balance import HBSettings
from fe.reduction import JointBank
from ident.identify import identify_modes
from ident.modal_data import MeasuredData
from runs.campaign import Campaign, HBProtocol
from runs.stepped_sine import run_campaign

CHI_RANGE = (-0.7, -0.25)
TOP_SLIP = 0.4
#: the top level's linear slip of another law, in its slip scale
TOP_SLIP_OTHER = 4.0
#: smallest slider slip of the Jenkins banks, in phi_max (below the level-1 slip)
BANK_LOW = 1e-5
SIGMA_OMEGA2, SIGMA_ZETA = 1e-5, 5e-4
HB = HBSettings(n_harmonics=5, n_time=64, odd_only=True)
#: lines: from ``-BAND_HALF_POWER`` to ``+BAND_HALF_POWER / 2`` half-power bandwidths about
#: the stuck frequency, ``LINES`` of them
BAND_HALF_POWER, LINES = 3.0, 41


def _receptance(nc, red, load, lines, force):
    """(receptance (levels, lines) at the response DOF, fallback summary): the multi-
    harmonic stepped sine on the banks (an Iwan law's, 8 per octave, or the law's own),
    or first-harmonic balance line by line for a law without banks (module docstring)."""
    if nc.law_name == "iwan4" or nc.bank is not None:
        bank = JointBank.log_spaced(nc.joints, BANK_LOW * nc.phi_max, 8) \
            if nc.law_name == "iwan4" else nc.bank
        camp = Campaign(lines, force, load, np.array([nc.response_dof]), HBProtocol(HB))
        res = run_campaign(red, bank, camp, progress=False)
        return res.receptance[:, :, 0], res.fallback_summary()
    from fe.hb_exact import continuation_exact

    unit, rec, words = red.load(load), [], []
    for lv, F in enumerate(force):
        sols = continuation_exact(red, nc.joints, unit * F, 2 * np.pi * lines)
        rec.append([s.first_harmonic(red)[nc.response_dof] / F for s in sols])
        hit = [s.fallback for s in sols if s.fallback]
        if hit:
            words.append(f"level {lv + 1} (F = {F:.4g} N): {len(hit)} of {len(sols)} lines, "
                         f"first: {hit[0]}")
    return np.array(rec), "; ".join(words) or "none"


def simulate(case, seed: int, mode: int | None = None, top_slip: float | None = None,
             noise_seed: int | None = None) -> tuple[MeasuredData, dict]:
    """(table, truth) of :class:`cases.case.Case` ``case`` (a case file with joints and
    ``[measured] mode``, or the bending mode ``mode``) for ``seed`` (module docstring;
    ``top_slip``: the top level's linear slip in slip scales, default
    :data:`TOP_SLIP` or :data:`TOP_SLIP_OTHER`; ``noise_seed``: the run order and the
    noise from this seed instead, the seeded chi from ``seed``: several modes of one
    joint)."""
    from casefile.nonlinear import file_law, nonlinear_case

    rng = np.random.default_rng(seed)
    cf, _ = case.require("calibrated_file")()

    iwan = file_law(cf) == "iwan4"
    chi = float(rng.uniform(*CHI_RANGE)) if iwan else None
    if noise_seed is not None:
        rng = np.random.default_rng(noise_seed)
    if iwan:
        cf = dataclasses.replace(cf, interfaces=tuple(
            dataclasses.replace(i, chi=chi) if i.tangential == "joint" else i
            for i in cf.interfaces))
    model = case.fe_model()
    if mode is not None:          # the bending mode's index among the model's modes
        from casefile.nonlinear import N_RITZ_MODES

        order = model.bending_order(*model.modes(N_RITZ_MODES))
        if not np.any(order == int(mode)):
            raise ValueError(f"{cf.path}: no bending mode {mode} among the model's modes")
    nc = nonlinear_case(cf, model, mode=None if mode is None else
                        int(np.flatnonzero(order == int(mode))[0]) + 1)
    nc.require_point_drive("the stepped-sine virtual test (cases.stepped_sine_test)")
    red, k = nc.model, nc.mode - 1
    phi = red.basis[:, k]
    omega = float(red.omega[k])
    zeta = float(red.C[k, k] / (2.0 * omega))
    load = np.zeros(model.M.shape[0])
    load[nc.drive_dof] = 1.0
    slip_per_n = float(np.max(np.abs(model.slip_matrix @ phi))) * abs(phi[nc.drive_dof]) \
        / (2.0 * zeta * omega ** 2)          # linear modal slip at resonance per N
    top = top_slip if top_slip is not None else TOP_SLIP if iwan else TOP_SLIP_OTHER
    force = top * nc.phi_max / slip_per_n * 2.0 ** (np.arange(10) - 9.0)
    f0 = omega / (2 * math.pi)
    hp = 2.0 * zeta * f0
    lines = np.linspace(f0 - BAND_HALF_POWER * hp, f0 + 0.5 * BAND_HALF_POWER * hp, LINES)
    rec, fallbacks = _receptance(nc, red, load, lines, force)
    om2, ze = np.empty(force.size), np.empty(force.size)
    for lv in range(force.size):
        modes = identify_modes(lines, rec[lv], band=(lines[0], lines[-1]),
                               weighting="uniform", pseudo_modes=False)
        if not modes:
            raise RuntimeError(f"no mode identified at level {lv + 1}")
        m = max(modes, key=lambda m: float(np.max(np.abs(m.shape))))   # the dominant mode
        om2[lv], ze[lv] = m.omega2, m.zeta
    n = force.size
    label = mode if mode is not None else cf.measured.mode \
        if cf.measured is not None and cf.measured.mode else nc.mode
    run_order = rng.permutation(n) + 1
    data = MeasuredData(level=np.arange(1, n + 1), excitation=force,
                        omega2=om2 * (1.0 + SIGMA_OMEGA2 * rng.standard_normal(n)),
                        zeta=ze * (1.0 + SIGMA_ZETA * rng.standard_normal(n)),
                        mode=np.full(n, int(label)), run_order=run_order,
                        extra={"x_source": np.full(n, "simulated")})
    truth = {"chi": chi} if iwan else {"law": nc.law_name, "joints": nc.joint_source}
    return data, {**truth, "zeta_v": zeta, "f0_hz": f0, "phi_max": nc.phi_max,
                  "top_slip_over_phi_max": top, "forces_N": force.tolist(),
                  "fallbacks": fallbacks}


def main(argv=None) -> int:
    from cases.registry import resolve_case
    from ident.measured import write_measured

    args = list(argv if argv is not None else sys.argv[1:])
    top = None
    if "--top-slip" in args:
        i = args.index("--top-slip")
        top = float(args[i + 1])
        del args[i:i + 2]
    case_file, out, seed = args[:3]
    try:
        if len(args) < 4:
            data, truth = simulate(resolve_case(case_file), int(seed), top_slip=top)
        else:      # several bending modes of one joint, each its noise (seed + 100 mode)
            parts = [simulate(resolve_case(case_file), int(seed), mode=m, top_slip=top,
                              noise_seed=int(seed) + 100 * m)
                     for m in (int(t) for t in args[3].split(","))]
            data = MeasuredData.concatenate([d for d, _ in parts])
            truth = [t for _, t in parts]
    except ValueError as exc:       # a bad file, a base drive: one line, status 2
        print(f"cases.stepped_sine_test: error: {exc}", file=sys.stderr)
        return 2
    write_measured(out, data)
    print(f"wrote {out} (simulated): truth {truth}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
