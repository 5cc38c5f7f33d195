"""A stepped-sine series from its FRF files: one mode followed across levels, the table.

``shared/spec/measured-data.md``, "FRF files of a stepped-sine series". Each file is one
level (:mod:`ident.frf_files`; its header says what the level held, ``control``,
``run_order``, the drive point). :func:`identify_series` identifies every level
(:func:`ident.identify.identify`) and then makes the levels agree on the number of
modes in the band: a level whose automatic selection found more modes than most levels
(two poles on one resonance, typically at a level with little signal or a distorted
force-controlled FRF) is identified again with the common number, and says so. Each
mode gets the warnings of :mod:`ident.fit_quality` (fit error, stability, band
sensitivity). :func:`series_table` follows the modes across levels
(:func:`ident.tracking.track_modes`) and writes the measured-data table:

* force control: ``excitation`` = the held level; ``response_amplitude`` = the
  identified mode's amplitude at its resonance ``omega_d`` at the drive point,
  ``|H_r(omega_d)| F``: the mode's own FRF (residue over pole and its conjugate) in the
  file's quantity (m, m/s or m/s^2 per N) times the measured force there (the ``force``
  column, interpolated) or else the held level;
* response control: ``response_amplitude`` = the held level; ``excitation`` = the force
  at resonance: the ``force`` column at ``omega_d``, else the held level over the
  measured ``|H(omega_d)|`` (interpolated between lines).

``omega2_std``/``zeta_std`` are the identification's (:mod:`ident.pole_uncertainty`);
``x_fit_error`` and ``x_warning`` carry the fit warnings through a CSV round trip
(:func:`ident.modal_data.annotation_warnings`). A track shorter than 4 levels beside
longer ones is left out, with a note on the levels where it was seen.
:func:`load_series` reads either a measured-data table or the FRF files of a series.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ident.errors import InputError
from ident.fit_quality import band_shift, mode_warnings
from ident.frf_files import FRFSet, read_frf
from ident.frf_header import with_overrides
from ident.identify import identify
from ident.modal_data import MeasuredData, annotation_warnings
from ident.tracking import track_modes

MIN_LEVELS = 4


@dataclass
class LevelFit:
    """One level of a series: its FRF set, what it held and its identification."""

    frfset: FRFSet
    quantity: str
    control: str
    result: object                       # ident.identify.Identification
    warnings: list = field(default_factory=list)   # per mode: list of str

    @property
    def held(self) -> float | None:
        return self.frfset.excitation


def _identify(s: FRFSet, quantity, band, n_modes, options):
    try:
        return identify(s.freq_hz, s.frf, band=band, n_modes=n_modes, quantity=quantity,
                        **options)
    except ValueError as exc:
        raise InputError(f"{s.source or 'FRF set'}: {exc}") from None


def identify_series(sets, band=None, n_modes=None, quantity=None, options=None,
                    progress=None, check_band=True) -> list[LevelFit]:
    """Identify every FRF set of a series (module doc).

    Parameters
    ----------
    sets : list of FRFSet (one per level; header values already final).
    band : (lo, hi) Hz or None.   n_modes : modes per level or None (automatic).
    quantity : FRF quantity where a file does not state it (default receptance).
    options : further keyword arguments of :func:`ident.identify.identify`.
    progress : optional wrapper of an iterable (a progress bar).
    check_band : run the band-sensitivity check (one more identification per mode).
    """
    options = dict(options or {})
    fits = []
    iterator = progress(sets) if progress is not None else sets
    for s in iterator:
        q = s.quantity or quantity or "receptance"
        if s.quantity and quantity and s.quantity != quantity:
            raise InputError(f"{s.source}: the file holds {s.quantity}, --quantity says "
                             f"{quantity}")
        fits.append(LevelFit(s, q, s.control or "force",
                             _identify(s, q, band, n_modes, options)))
    notes = [[] for _ in fits]
    counts = np.array([len(f.result.modes) for f in fits])
    if n_modes is None and np.any(counts > 0):
        values, freq = np.unique(counts[counts > 0], return_counts=True)
        common = int(values[np.argmax(freq)])          # the smaller one on a tie
        agree = int(np.sum(counts == common))
        for k, f in enumerate(fits):
            if counts[k] > common:
                found = ", ".join(f"{m.frequency_hz:.6g}" for m in f.result.modes)
                f.result = _identify(f.frfset, f.quantity, band, common, options)
                notes[k].append(f"automatic selection found {counts[k]} modes ({found} Hz); "
                                f"identified with {common}, as at {agree} of {len(fits)} "
                                "levels")
    for k, f in enumerate(fits):
        def again(b, n, f=f):
            return _identify(f.frfset, f.quantity, b, n, options)

        f.warnings = [notes[k] + mode_warnings(
            f.result, i, band_shift(again, f.frfset.freq_hz, f.result, i) if check_band else None)
            for i in range(len(f.result.modes))]
    return fits


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
    ``A/(i w - lambda) + conj(A)/(i w - conj(lambda))`` at ``w = Im(lambda)``, times
    ``w`` (mobility) or ``w^2`` (accelerance)."""
    lam, a = complex(mode.pole), complex(np.atleast_1d(mode.shape)[point])
    w = lam.imag
    h = a / (1j * w - lam) + np.conj(a) / (1j * w - np.conj(lam))
    power = {"receptance": 0, "mobility": 1, "accelerance": 2}[quantity]
    return float(abs(h) * w ** power)


def _amplitudes(f: LevelFit, mode):
    """(excitation, response_amplitude, note) of one mode of one level (module doc)."""
    s = f.frfset
    p, note = drive_point(s)
    f_d = mode.pole.imag / (2 * np.pi)
    force = None if s.force is None else float(np.interp(f_d, s.freq_hz, s.force))
    if f.control == "response":
        if force is None:
            force = s.excitation / float(np.interp(f_d, s.freq_hz, np.abs(s.frf[:, p])))
        return force, s.excitation, note
    amp = mode_frf_at_resonance(mode, p, f.quantity) * (s.excitation if force is None else force)
    return s.excitation, amp, note


def series_table(fits: list[LevelFit]) -> MeasuredData:
    """The measured-data table of an identified series (module doc)."""
    controls = {f.control for f in fits}
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
    try:
        order, rows = track_modes([f.held for f in fits], [f.result.modes for f in fits])
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if not rows:
        raise InputError("no mode identified at any level")
    level_of = {int(k): n + 1 for n, k in enumerate(order)}
    labels = np.array([r[2] for r in rows])
    n_levels = {lab: int(np.sum(labels == lab)) for lab in set(labels.tolist())}
    keep = np.array([n_levels[lab] >= MIN_LEVELS or max(n_levels.values()) < MIN_LEVELS
                     for lab in labels])
    out = {k: [] for k in ("level", "excitation", "omega2", "zeta", "mode", "response",
                           "run", "w_std", "z_std", "f", "stab", "mac", "err", "src", "warn")}
    dropped = [(r, n_levels[r[2]]) for r, ok in zip(rows, keep) if not ok]
    for (k, i, lab, m), ok in zip(rows, keep):
        if not ok:
            continue
        f = fits[k]
        mode = f.result.modes[i]
        exc, amp, note = _amplitudes(f, mode)
        warn = list(f.warnings[i]) + ([note] if note else [])
        warn += [f"a pole at {fits[kk].result.modes[ii].frequency_hz:.6g} Hz seen at "
                 f"{n} level(s) only was left out" for (kk, ii, _, _), n in dropped if kk == k]
        for key, v in zip(out, (level_of[k], exc, mode.omega2, mode.zeta, lab, amp,
                                run_order[k], mode.omega2_std, mode.zeta_std,
                                mode.frequency_hz, mode.stability, m, f.result.fit_error,
                                Path(f.frfset.source).name, " | ".join(warn))):
            out[key].append(v)
    stds = np.array([out["w_std"], out["z_std"]], float)
    has_std = bool(np.all(np.isfinite(stds) & (stds > 0)))
    control = fits[0].control
    data = MeasuredData(
        level=out["level"], excitation=out["excitation"], omega2=out["omega2"],
        zeta=out["zeta"], mode=out["mode"], run_order=out["run"],
        response_amplitude=out["response"], omega2_std=stds[0] if has_std else None,
        zeta_std=stds[1] if has_std else None, control=[control] * len(out["level"]),
        extra={"x_frequency_hz": np.array(out["f"]), "x_stability": np.array(out["stab"]),
               "x_mac": np.array(out["mac"], float), "x_fit_error": np.array(out["err"]),
               "x_source": np.array(out["src"], dtype=str),
               "x_warning": np.array(out["warn"], dtype=str)},
        source="FRF series")
    data.warnings = annotation_warnings(data)
    if not has_std:
        data.warnings.append("FRF series: no identification uncertainty at some level: "
                             "omega2_std and zeta_std left out")
    return data


def is_frf_file(path) -> bool:
    """True for a universal file or a CSV whose first line is a ``#`` header or
    ``freq_hz``; False for a measured-data table."""
    path = Path(path)
    if path.suffix.lower() in (".uff", ".unv", ".uf"):
        return True
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            for line in fh:
                if line.strip():
                    first = line.strip()
                    return first == "-1" or first.startswith("#") or first.startswith("freq_hz")
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from None
    return False


def read_series_sets(paths, excitation=None, control=None, run_order=None, reference=None):
    """The FRF sets of a series with command-line values overriding the files'
    (``excitation``, ``run_order``: one per file; ``control``, ``reference``: one)."""
    paths = [str(p) for p in paths]
    for name, values in (("--excitation", excitation), ("--run-order", run_order)):
        if values is not None and len(values) != len(paths):
            raise InputError(f"{name} needs one value per FILE: got {len(values)} values "
                             f"for {len(paths)} files")
    sets = []
    for k, p in enumerate(paths):
        s = read_frf(p)
        sets.append(with_overrides(
            s, excitation=None if excitation is None else excitation[k], control=control,
            run_order=None if run_order is None else run_order[k], reference=reference))
    return sets


def load_series(paths, band=None, n_modes=None, quantity=None, excitation=None,
                control=None, run_order=None, reference=None, options=None,
                progress=None) -> MeasuredData:
    """A measured-data table (one CSV file) or the FRF files of a series (one per level,
    identified first): the input of ``iwanfe estimate`` and ``iwanfe diagnose``."""
    from ident.measured import read_measured

    paths = [str(p) for p in paths]
    if not paths:
        raise InputError("no input file")
    frf = [is_frf_file(p) for p in paths]
    if not any(frf):
        if len(paths) > 1:
            raise InputError(f"{paths[1]}: one measured-data table at a time (or the FRF "
                             "files of one series)")
        return read_measured(paths[0])
    if not all(frf):
        raise InputError(f"{paths[frf.index(False)]}: not an FRF file (the other files are): "
                         "give either one measured-data table or the FRF files of a series")
    sets = read_series_sets(paths, excitation, control, run_order, reference)
    fits = identify_series(sets, band=band, n_modes=n_modes, quantity=quantity,
                           options=options, progress=progress)
    return series_table(fits)
