"""The measured-data table of an identified stepped-sine series.

``docs/formats/measured-data.md``: :func:`series_table` follows the modes of the levels
of :func:`ident.series.identify_series` across levels (:func:`ident.tracking.track_modes`)
and writes one row per mode and level:

* force control: ``excitation`` = the held level; ``response_amplitude`` = the
  identified mode's amplitude at its resonance ``omega_d`` at the drive point,
  ``|H_r(omega_d)| F``: the mode's own FRF (residue over pole and its conjugate) in the
  file's quantity (m, m/s or m/s^2 per N) times the measured force there (the ``force``
  column, interpolated) or else the held level; where the amplitude-dependent refit was
  used (:mod:`ident.amplitude_poles`), the peak amplitude its pole refers to
  (``response_at_peak``);
* response control: ``response_amplitude`` = the held level; ``excitation`` = the force
  at resonance: the ``force`` column at ``omega_d``, else the held level over the
  measured ``|H(omega_d)|`` (interpolated between lines).

* random excitation (``# test = random``): ``excitation`` = the drive RMS,
  ``response_amplitude`` = the mode's response RMS at the drive point
  (:func:`ident.random_frf.mode_response_rms`: the mode's own FRF times the file's
  ``force_psd``, else a drive flat over the lines); column ``test = random``. A level not
  stated as random whose file looks averaged (coherence column, an averaged flat drive
  spectrum, uniform line noise: :mod:`ident.random_evidence`) gets its numbers in
  ``x_warning`` and one line for the series in the table's warnings.

``run_order`` comes from the files (all or none; default the file order); files that
held the same level (equal to 1e-9) are repeats of one level (rows sharing ``level``);
``omega2_std``/``zeta_std`` from the identification (:mod:`ident.pole_uncertainty`;
left out when a level has none), ``x_omega2_slope``/``x_zeta_slope`` the within-level
slopes ``d ln omega2 / d ln a``, ``d ln zeta / d ln a`` of the amplitude-dependent refit
(NaN where it was not used), ``x_fit_error`` and ``x_warning`` carry the fit
warnings through a CSV round trip (:func:`ident.modal_data.annotation_warnings`). A
track shorter than 4 levels beside longer ones is left out, with a note on the levels
where it was seen; when no track reaches 4 of 4 or more levels the table is refused
with the tracks found.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident.errors import InputError
from ident.frf_files import FRFSet
from ident.modal_data import MeasuredData, annotation_warnings
from ident.poles import QUANTITY_POWER, modal_receptance
from ident.random_evidence import GIVEN_AS, random_evidence, series_warning
from ident.random_frf import mode_response_rms
from ident.tracking import track_modes

MIN_LEVELS = 4


def drive_point(s: FRFSet) -> tuple[int, str | None]:
    """Index of the drive point among the response points, and a note if it is a guess."""
    if s.reference is not None and s.reference in s.points:
        return s.points.index(s.reference), None
    if len(s.points) == 1:
        return 0, None
    return 0, (f"drive point {s.reference!r} not among the response points: response "
               f"amplitude taken at point {s.points[0]}")


def mode_frf_at_resonance(mode, point: int, quantity: str) -> float:
    """``|H_r(omega_d)|`` of one identified mode at a point, in the FRF's quantity per N:
    its modal receptance (:func:`ident.poles.modal_receptance`) at
    ``omega_d = Im(lambda)``, times ``omega_d`` (mobility) or ``omega_d^2``
    (accelerance)."""
    w = mode.pole.imag
    h = modal_receptance(mode.pole, np.atleast_1d(mode.shape)[point], w / (2 * np.pi))
    return float(abs(h[0, 0]) * w ** QUANTITY_POWER[quantity])


def _amplitudes(f, mode):
    """(excitation, response_amplitude, note) of one mode of one level (module doc)."""
    s = f.frfset
    p, note = drive_point(s)
    f_d = mode.pole.imag / (2 * np.pi)
    force = None if s.force is None else float(np.interp(f_d, s.freq_hz, s.force))
    if s.test == "random":
        return s.excitation, mode_response_rms(mode, p, f.quantity, s.freq_hz,
                                               s.excitation, s.force_psd), note
    if f.control == "response":
        if force is None:
            force = s.excitation / float(np.interp(f_d, s.freq_hz, np.abs(s.frf[:, p])))
        return force, s.excitation, note
    if np.isfinite(mode.response_at_peak):      # the amplitude the pole refers to
        return s.excitation, mode.response_at_peak, note
    amp = mode_frf_at_resonance(mode, p, f.quantity) * (s.excitation if force is None else force)
    return s.excitation, amp, note


def _check_series(fits: list) -> tuple[set, list, np.ndarray]:
    """One test type and one control, every held level known, run orders all or none:
    the test types (one), the random-looking signature of each stepped-sine level and
    the run orders."""
    controls = {f.control for f in fits}
    tests = {f.frfset.test or "stepped-sine" for f in fits}
    if len(tests) > 1:
        raise InputError("the files mix test = stepped-sine and random; one series has one "
                         "test type (give --test to override the files)")
    signature = [None if f.frfset.test == "random" else
                 random_evidence(f.frfset, f.result.modes, f.quantity) for f in fits]
    if len(controls) > 1:
        raise InputError("the files mix control = force and response; one series has one "
                         "control (give --control to override the files)")
    missing = [f.frfset.source for f in fits if f.held is None]
    if missing:
        raise InputError(f"{missing[0]}: the level it held is unknown: give --excitation V "
                         "per file, a CSV line '# excitation = V' or a UFF ID line "
                         "'excitation=V'")
    given = [f.frfset.run_order is not None for f in fits]
    if any(given) and not all(given):
        raise InputError(f"{fits[given.index(False)].frfset.source}: no run_order while "
                         "other files state one; give all or none (--run-order)")
    run_order = (np.array([f.frfset.run_order for f in fits]) if all(given)
                 else np.arange(1, len(fits) + 1))
    return tests, signature, run_order


@dataclass
class _Tracks:
    """The tracked rows ``(level index, mode index, label, MAC)``
    (:func:`ident.tracking.track_modes`), the level number of each file (repeats of one
    held level share it), which rows are kept, and those left out with their track's
    level count."""

    rows: list
    level_of: dict[int, int]
    keep: np.ndarray
    dropped: list


def _tracks(fits: list) -> _Tracks:
    """The modes of the levels followed across levels (:class:`_Tracks`)."""
    try:
        order, rows = track_modes([f.held for f in fits], [f.result.modes for f in fits])
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if not rows:
        raise InputError("no mode identified at any level")
    held = np.array([fits[int(k)].held for k in order], float)
    same = np.r_[False, np.abs(np.diff(held)) <= 1e-9 * np.abs(held[1:])]
    level_of = {int(k): int(v) for k, v in zip(order, np.cumsum(~same))}   # repeats share
    return _Tracks(rows, level_of, *_kept(fits, rows, level_of))


def _kept(fits: list, rows: list, level_of: dict[int, int]) -> tuple[np.ndarray, list]:
    """Which rows belong to a track of :data:`MIN_LEVELS` levels or more (all when none
    does and the series is too short to ask it), and the rows left out with their
    track's level count; refused when no track is long enough in a long series."""
    labels = np.array([r[2] for r in rows])
    n_levels = {lab: int(np.sum(labels == lab)) for lab in set(labels.tolist())}
    if len(fits) >= MIN_LEVELS and max(n_levels.values()) < MIN_LEVELS:
        tracks = "; ".join(
            f"mode {lab}: " + ", ".join(f"level {level_of[k]} "
                                        f"{fits[k].result.modes[i].frequency_hz:.5g} Hz"
                                        for k, i, lb, _ in rows if lb == lab)
            for lab in sorted(n_levels))
        raise InputError(f"no mode could be followed over {MIN_LEVELS} of the {len(fits)} "
                         f"levels (a mode moved by more than 5 % or changed shape, MAC < 0.8, "
                         f"between levels): {tracks}; identify one mode per level with "
                         "--band around it and --modes 1")
    keep = np.array([n_levels[lab] >= MIN_LEVELS or max(n_levels.values()) < MIN_LEVELS
                     for lab in labels])
    dropped = [(r, n_levels[r[2]]) for r, ok in zip(rows, keep) if not ok]
    return keep, dropped


#: Keys of the columns :func:`_columns` collects, in the order of its values.
_COLUMNS = ("level", "excitation", "omega2", "zeta", "mode", "response", "run", "w_std",
            "z_std", "f", "stab", "mac", "err", "src", "warn", "w_slope", "z_slope")


def _columns(fits: list, tracks: _Tracks, run_order: np.ndarray, signature: list
             ) -> dict[str, list]:
    """The table's values of the kept rows, column by column (:data:`_COLUMNS`), the
    warnings of each row joined by `` | ``."""
    level_of, dropped = tracks.level_of, tracks.dropped
    out = {k: [] for k in _COLUMNS}
    for (k, i, lab, m), ok in zip(tracks.rows, tracks.keep):
        if not ok:
            continue
        f = fits[k]
        mode = f.result.modes[i]
        exc, amp, note = _amplitudes(f, mode)
        warn = list(f.warnings[i]) + ([note] if note else [])
        if signature[k] is not None and signature[k].looks_random:
            warn.append(f"{GIVEN_AS}, but looks like a random test: {signature[k].line()}")
        warn += [f"a pole at {fits[kk].result.modes[ii].frequency_hz:.6g} Hz seen at "
                 f"{n} level(s) only was left out" for (kk, ii, _, _), n in dropped if kk == k]
        for key, v in zip(out, (level_of[k], exc, mode.omega2, mode.zeta, lab, amp,
                                run_order[k], mode.omega2_std, mode.zeta_std,
                                mode.frequency_hz, mode.stability, m, f.result.fit_error,
                                Path(f.frfset.source).name, " | ".join(warn),
                                mode.omega2_slope, mode.zeta_slope)):
            out[key].append(v)
    return out


def _table(out: dict[str, list], control: str, test: str) -> MeasuredData:
    """The measured-data table of the collected columns, with its warnings (the
    uncertainties left out unless every row has them)."""
    stds = np.array([out["w_std"], out["z_std"]], float)
    has_std = bool(np.all(np.isfinite(stds) & (stds > 0)))
    data = MeasuredData(
        level=out["level"], excitation=out["excitation"], omega2=out["omega2"],
        zeta=out["zeta"], mode=out["mode"], run_order=out["run"],
        response_amplitude=out["response"], omega2_std=stds[0] if has_std else None,
        zeta_std=stds[1] if has_std else None, control=[control] * len(out["level"]),
        test=[test] * len(out["level"]),
        extra={"x_frequency_hz": np.array(out["f"]), "x_stability": np.array(out["stab"]),
               "x_mac": np.array(out["mac"], float), "x_fit_error": np.array(out["err"]),
               "x_source": np.array(out["src"], dtype=str),
               "x_warning": np.array(out["warn"], dtype=str),
               "x_omega2_slope": np.array(out["w_slope"], float),
               "x_zeta_slope": np.array(out["z_slope"], float)},
        source="FRF series")
    data.warnings = annotation_warnings(data)
    if not has_std:
        data.warnings.append("FRF series: no identification uncertainty at some level: "
                             "omega2_std and zeta_std left out")
    return data


def series_table(fits) -> MeasuredData:
    """The measured-data table of an identified series (module doc).

    ``fits``: the :class:`ident.series.LevelFit` of every level."""
    tests, signature, run_order = _check_series(fits)
    out = _columns(fits, _tracks(fits), run_order, signature)
    data = _table(out, fits[0].control, tests.pop())
    if line := series_warning(signature):      # one line for the series, not one per level
        data.warnings = [w for w in data.warnings if GIVEN_AS not in w] + [line]
    return data
