"""``iwanfe ringdown``: a simulated free decay of a case's mode, written as a test record.

The shaker switched off at phase resonance: the mode's periodic orbit at the start
amplitude (a point of its EPMC backbone on the joints the integration uses,
:attr:`casefile.jointed.NonlinearCase.time_law`: the Jenkins-bank path, or for a law with
no bank (Bouc-Wen) its exact first harmonic and its own step, no energy balance;
:func:`fe.epmc.solve_epmc`, Krack 2015) is the initial state, or an
impulse at the drive point (:func:`runs.ringdown.impulse_start`) scaled so that the
stuck-joint mode would reach the start amplitude. :func:`runs.ringdown.ring_down`
integrates the reduced model with its joints (average-acceleration rule, pre-warped
time axis, energy balance) and the record is written chunk by chunk to a free-decay
CSV (``docs/formats/measured-data.md``, ``# test = free-decay``): the displacement at the
case's drive and response points. :mod:`cases.ringdown_routes` then identifies it and
compares it with the backbone and the response-controlled virtual test.

The start amplitude is the largest joint slip over its ``phi_max`` (the joint that slips
most in the stuck-joint mode): default 0.5. SI units: s, m, N.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from runs.ringdown import FreeDecayRecord, impulse_start, orbit_start, ring_down, warped_step

__all__ = ["RingdownSettings", "ringdown_case", "simulate_ringdown", "write_record_header",
           "append_record_rows", "RECORD_FILE"]

RECORD_FILE = "free_decay.csv"
STARTS = ("orbit", "impulse")


@dataclass(frozen=True)
class RingdownSettings:
    """What to simulate: ``mode`` (1-based), start ``amplitude`` (largest slip /
    phi_max), ``cycles`` (periods of the stuck-joint mode), ``steps_per_period``,
    ``start`` (``orbit`` or ``impulse``)."""

    mode: int
    amplitude: float = 0.5
    cycles: float = 500.0
    steps_per_period: int = 64
    start: str = "orbit"

    def __post_init__(self):
        if not self.mode >= 1:
            raise ValueError(f"--mode must be >= 1, got {self.mode}")
        if not (np.isfinite(self.amplitude) and self.amplitude > 0):
            raise ValueError(f"--amplitude must be > 0 (slip / phi_max), got {self.amplitude}")
        if not (np.isfinite(self.cycles) and 1 <= self.cycles <= 1e5):
            raise ValueError(f"--cycles must be in 1..100000, got {self.cycles}")
        if not 16 <= self.steps_per_period <= 4096:
            raise ValueError(f"--steps-per-period must be in 16..4096, got "
                             f"{self.steps_per_period}")
        if self.start not in STARTS:
            raise ValueError(f"--start must be one of {', '.join(STARTS)}, got {self.start!r}")


def ringdown_case(name: str, mode: int, model=None):
    """The jointed model of case ``name`` (a shipped name or a case file; ``model``: an
    ``updated_model.json`` of it) studying ``mode``: the one place this command gets a
    case (its ``nonlinear_model`` capability, :mod:`cases.case`)."""
    from cases.registry import resolve_case

    case = resolve_case(name, model=model).nonlinear_model(mode=mode)
    case.require_point_drive("ringdown")      # its impulse and its drive amplitude
    return case


def settings_hash(case, settings: RingdownSettings) -> str:
    """SHA-256 of the case's reduced model and joints and the settings (a stored record
    is reused only if it matches)."""
    h = hashlib.sha256()
    m, b = case.model, case.bank
    joints = (b.stiffness, b.slip_limit) if b is not None else law_arrays(case.time_law)
    for a in (m.basis, m.M, m.K, m.C, m.G, m.K_T, *joints):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(json.dumps(asdict(settings), sort_keys=True).encode())
    h.update(f"{case.name}:{case.drive_dof}:{case.response_dof}".encode())
    return h.hexdigest()


def law_arrays(law) -> tuple:
    """The arrays that define a joint law other than a bank (its class name, ``K_T`` and
    every per-joint parameter array it holds), for the record's hash."""
    arrays = [np.frombuffer(type(law).__name__.encode(), dtype=np.uint8)]
    arrays += [np.asarray(v, dtype=float) for k, v in sorted(vars(law).items())
               if isinstance(v, np.ndarray)]
    return tuple(arrays)


def write_record_header(path, points) -> None:
    """Start a free-decay CSV: the spec's header lines, then ``time_s`` and one column per
    point (displacement, m). What was simulated is in ``record.json`` beside it."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# test = free-decay\n# quantity = displacement\n")
        fh.write(",".join(["time_s", *points]) + "\n")


def append_record_rows(path, time_s, response) -> None:
    """Append samples (``time_s`` (n,), ``response`` (n, n_points)) and flush them to
    disk."""
    block = np.column_stack([np.asarray(time_s, float), np.asarray(response, float)])
    with open(path, "a", encoding="utf-8") as fh:
        np.savetxt(fh, block, delimiter=",", fmt="%.17g")
        fh.flush()
        os.fsync(fh.fileno())


def _start_state(case, settings, dt):
    """Initial state and what it is: the EPMC orbit (the time domain's path: banks, or the
    law's exact first harmonic) at the start amplitude, or an impulse at the drive
    point."""
    from fe.epmc import linear_mode

    model, bank = case.model, case.time_law
    w0, phi = linear_mode(model, settings.mode)
    gphi = np.abs(model.G @ phi)
    j = int(np.argmax(gphi))
    slip = settings.amplitude * float(case.phi_max_per_joint[j])
    if settings.start == "impulse":
        load = case.load()
        impulse = slip * w0 / (gphi[j] * abs(load @ phi))   # stuck mode: slip = |G phi| a
        return impulse_start(model, bank, load, impulse), {
            "start": "impulse", "impulse_Ns": float(impulse), "joint": j + 1,
            "slip_m": slip}
    pt, how = _start_orbit(case, settings.mode, slip)
    state = orbit_start(model, bank, pt.harmonics, pt.q[-1], float(pt.omega[-1]), dt,
                        case.n_time)
    return state, {"start": "orbit", "path": case.time_path, "joint": j + 1, "slip_m": slip,
                   "drive_amplitude_m": float(pt.dof_amplitude(case.drive_dof)[-1]),
                   "frequency_hz": float(pt.frequency_hz[-1]), "zeta": float(pt.zeta[-1]),
                   **({"reached": how} if how else {})}


#: points of the continuation that reaches a start orbit a cold start does not
START_CONTINUATION = 24


def _start_orbit(case, mode: int, slip: float):
    """The EPMC point at ``slip`` (its last point is the orbit) and how it was reached:
    solved there (``None``), or, when that cold start fails (one Jenkins slider per joint
    on the bank path: a force with kinks), continued from a hundredth of the slip
    (:data:`START_CONTINUATION` points; said in the record). RuntimeError otherwise."""
    from fe.epmc import epmc_backbone, solve_epmc

    model, joints = case.model, case.joint_harmonics(case.time_path)
    try:
        return solve_epmc(model, joints, mode, slip), None
    except RuntimeError as exc:
        cold = str(exc)
    try:
        pt = epmc_backbone(model, joints, mode, np.geomspace(1e-2 * slip, slip,
                                                              START_CONTINUATION))
    except RuntimeError as exc:
        raise RuntimeError(f"start orbit: {cold}; continued from 0.01 x the slip: "
                           f"{exc}") from None
    return pt, (f"continued over {START_CONTINUATION} points from 0.01 x the slip (a cold "
                f"start did not converge: {cold})")


def simulate_ringdown(case, settings: RingdownSettings, out: Path | None = None,
                      progress=None) -> tuple[FreeDecayRecord, dict]:
    """Integrate the free decay of ``settings.mode`` of ``case`` (module docstring).

    With ``out``, the record is written to ``out/free_decay.csv`` as it is computed and
    ``out/record.json`` (hash, start, energy balance) once it is complete; a complete
    record of the same hash there is loaded instead of recomputed.

    Returns
    -------
    (FreeDecayRecord, info dict: start, energy balance, step, timing)
    """
    from fe.epmc import linear_mode

    model = case.model
    if settings.mode > model.n_reduced:
        raise ValueError(f"--mode must be in 1..{model.n_reduced}, got {settings.mode}")
    digest = settings_hash(case, settings)
    if out is not None:
        done = _load_record(Path(out), digest)
        if done is not None:
            return done
    w0 = linear_mode(model, settings.mode)[0]
    dt, dt_rec = warped_step(w0, settings.steps_per_period)
    state, start = _start_state(case, settings, dt)
    outputs = model.basis[[case.drive_dof, case.response_dof]]
    points = ("drive", "response")
    if out is not None:
        path = Path(out) / RECORD_FILE
        write_record_header(path, points)

        def on_chunk(t, y, s):
            return append_record_rows(path, t, y)
    else:
        on_chunk = None
    t0 = time.perf_counter()
    rec = ring_down(model, case.time_law, state, w0, settings.cycles, outputs, points,
                    settings.steps_per_period, progress=progress, on_chunk=on_chunk,
                    start=settings.start)
    elapsed = time.perf_counter() - t0
    e = rec.energy
    info = {"hash": digest, "case": case.name, "mode": settings.mode,
            "settings": asdict(settings), "start": start,
            "omega0_rad_s": float(w0), "dt_integration_s": rec.dt_integration,
            "dt_record_s": float(dt_rec), "samples": int(rec.time_s.size),
            "drive_dof": int(case.drive_dof), "response_dof": int(case.response_dof),
            "energy_J": None if e is None else {
                "viscous": e.viscous, "joint_dissipation": e.joint_dissipation,
                "kinetic_change": e.kinetic, "strain_change": e.strain,
                "joint_stored_change": e.joint_stored, "residual": e.residual,
                "relative_residual": e.relative_residual},
            "newton_iterations": rec.newton_iterations, "integration_s": elapsed}
    if out is not None:
        np.savez(Path(out) / "record.tmp.npz", slip=rec.slip)
        os.replace(Path(out) / "record.tmp.npz", Path(out) / "record_slip.npz")
        _write_json(Path(out) / "record.json", info)
    return rec, info


def _write_json(path: Path, obj) -> None:
    from runs.jsonio import to_jsonable

    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(to_jsonable(obj), indent=1))
    os.replace(tmp, path)


def _load_record(out: Path, digest: str):
    """A complete stored record of hash ``digest`` (``record.json`` is written last)."""
    meta, csv, slip = out / "record.json", out / RECORD_FILE, out / "record_slip.npz"
    if not (meta.exists() and csv.exists() and slip.exists()):
        return None
    info = json.loads(meta.read_text())
    if info.get("hash") != digest:
        return None
    data = np.loadtxt(csv, delimiter=",", skiprows=_header_lines(csv), ndmin=2)
    from fe.newmark import EnergyBalance

    e = info["energy_J"]
    with np.load(slip) as d:
        s = d["slip"]
    energy = None if e is None else EnergyBalance(
        0.0, e["viscous"], e["joint_dissipation"], e["kinetic_change"], e["strain_change"],
        e["joint_stored_change"])
    rec = FreeDecayRecord(time_s=data[:, 0], response=data[:, 1:], points=("drive", "response"),
                          slip=s, energy=energy,
                          dt_integration=info["dt_integration_s"],
                          steps_per_period=info["settings"]["steps_per_period"],
                          omega0=info["omega0_rad_s"], start=info["settings"]["start"],
                          newton_iterations=info["newton_iterations"])
    info["loaded"] = True
    return rec, info


def _header_lines(path: Path) -> int:
    """Number of lines before the data (comment lines and the column header)."""
    n = 0
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            n += 1
            if not line.startswith("#"):
                return n
    return n
