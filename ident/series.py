"""A stepped-sine series from its FRF files: identification of every level, loading.

``docs/formats/measured-data.md``, "FRF files of a stepped-sine series". Each file is one
level (:mod:`ident.frf_files`; its header says what the level held, ``control``,
``run_order``, the drive point). :func:`identify_series` identifies every level
(:func:`ident.identify.identify`) and then makes the levels agree on the number of
modes in the band (:func:`ident.tracking.agree_on_modes`: two poles on one resonance
become one; a level with more modes than most levels is identified again with the
common number; the level's warnings say so). With ``amplitude_refit`` (opt-in) a
force-controlled level's poles are refitted at their peak amplitudes
(:mod:`ident.amplitude_poles`). Each mode gets the warnings of
:mod:`ident.fit_quality` (fit error, stability, band sensitivity).
:func:`ident.series_table.series_table` turns the levels into the measured-data table.
:func:`load_series` reads either a measured-data table or the FRF files of a series
(identified first): the input of ``iwanfe estimate`` and ``iwanfe diagnose``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ident.amplitude_poles import amplitude_poles
from ident.errors import InputError
from ident.fit_quality import band_shift, mode_warnings
from ident.frf_files import FRFSet, read_frf
from ident.frf_header import with_overrides
from ident.identify import identify
from ident.modal_data import MeasuredData
from ident.series_table import drive_point, series_table
from ident.tracking import agree_on_modes, one_resonance


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


def refits_amplitude(s: FRFSet) -> bool:
    """Whether a level's poles are refitted with their amplitude dependence: force
    control, stepped sine (:mod:`ident.amplitude_poles`)."""
    return (s.control or "force") == "force" and (s.test or "stepped-sine") != "random"


def with_amplitude_poles(s: FRFSet, freq_hz, frf, quantity, result):
    """``result`` (an Identification of ``frf`` (K, P) at ``freq_hz``, lines of ``s``)
    with the poles at each mode's peak amplitude (:func:`ident.amplitude_poles
    .amplitude_poles`) when the level :func:`refits_amplitude`; a note when the refit
    is not used."""
    if not refits_amplitude(s) or not result.modes:
        return result
    lo, hi = result.band_hz
    keep = (freq_hz >= lo) & (freq_hz <= hi) & (freq_hz > 0)
    held = 1.0 if s.excitation is None else abs(float(s.excitation))
    force = (np.full(keep.sum(), held) if s.force is None
             else np.interp(freq_hz[keep], s.freq_hz, np.abs(s.force)))
    modes, note = amplitude_poles(freq_hz[keep], np.asarray(frf).reshape(len(freq_hz), -1)[keep],
                                  force, quantity, result.modes, drive_point(s)[0],
                                  result.pseudo_poles)
    return replace(result, modes=modes, notes=list(result.notes) + ([note] if note else []))


def identify_level(s: FRFSet, quantity, band=None, n_modes=None, options=None,
                   amplitude=False):
    """One level identified (:func:`ident.identify.identify`); with ``amplitude`` its
    poles then refitted at their peak amplitudes where :func:`refits_amplitude`."""
    try:
        res = identify(s.freq_hz, s.frf, band=band, n_modes=n_modes, quantity=quantity,
                       **(options or {}))
    except ValueError as exc:
        raise InputError(f"{s.source or 'FRF set'}: {exc}") from None
    return with_amplitude_poles(s, s.freq_hz, s.frf, quantity, res) if amplitude else res


def _fewer_modes(s: FRFSet, quantity, band, n, options, before):
    """Level ``s`` identified again with ``n`` modes (:func:`ident.tracking
    .agree_on_modes`), with the amplitude-dependent refit. A mode of ``before`` that is
    not one resonance with a kept mode (:func:`ident.tracking.one_resonance`) is a
    resonance the series leaves out, which the refit would take for an amplitude
    dependence: the level then keeps the linear fit, with a note."""
    res = identify_level(s, quantity, band, n, options)
    left = [m.frequency_hz for m in before.modes
            if not any(one_resonance([m, k]) for k in res.modes)]
    if left and refits_amplitude(s):
        return replace(res, notes=list(res.notes) + [
            f"a resonance at {', '.join(f'{x:.6g}' for x in left)} Hz left out of this "
            "level's band: linear fit kept (no amplitude-dependent refit)"])
    return with_amplitude_poles(s, s.freq_hz, s.frf, quantity, res)


def identify_series(sets, band=None, n_modes=None, quantity=None, options=None,
                    progress=None, check_band=True, amplitude_refit=False) -> list[LevelFit]:
    """Identify every FRF set of a series (module doc).

    Parameters
    ----------
    sets : list of FRFSet (one per level; header values already final).
    band : (lo, hi) Hz or None.   n_modes : modes per level or None (automatic).
    quantity : FRF quantity where a file does not state it (default receptance).
    options : further keyword arguments of :func:`ident.identify.identify`.
    progress : optional wrapper of an iterable (a progress bar).
    check_band : run the band-sensitivity check (one more identification per mode).
    amplitude_refit : refit force-controlled levels at their peak amplitudes
        (:mod:`ident.amplitude_poles`; opt-in, docs/commands.md says why).
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
                             identify_level(s, q, band, n_modes, options, amplitude_refit)))
    notes = [[] for _ in fits]
    if n_modes is None:
        def refit(k, n):
            if not amplitude_refit:
                return identify_level(fits[k].frfset, fits[k].quantity, band, n, options)
            return _fewer_modes(fits[k].frfset, fits[k].quantity, band, n, options,
                                fits[k].result)

        results, notes = agree_on_modes([f.result for f in fits], refit)
        for f, res in zip(fits, results):
            f.result = res
    for k, f in enumerate(fits):
        s = f.frfset
        def narrow_refit(freq_hz, frf, narrow, s=s):
            return with_amplitude_poles(s, freq_hz, frf, "receptance", narrow)

        f.warnings = [notes[k] + list(f.result.notes) + mode_warnings(
            f.result, i, band_shift(s.freq_hz, s.frf, f.quantity, f.result, i, options,
                                    narrow_refit if amplitude_refit else None)
            if check_band else None) for i in range(len(f.result.modes))]
    return fits


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


def read_series_sets(paths, excitation=None, control=None, run_order=None, reference=None,
                     test=None):
    """The FRF sets of a series with command-line values overriding the files'
    (``excitation``, ``run_order``: one per file; ``control``, ``reference``, ``test``:
    one)."""
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
            run_order=None if run_order is None else run_order[k], reference=reference,
            test=test))
    return sets


def load_series(paths, band=None, n_modes=None, quantity=None, excitation=None,
                control=None, run_order=None, reference=None, options=None,
                progress=None, test=None, decay_options=None,
                amplitude_refit=False) -> MeasuredData:
    """A measured-data table (one CSV file), the FRF files of a series (one per level,
    identified first) or a free-decay time record (:mod:`ident.free_decay_table`):
    the input of ``iwanfe estimate`` and ``iwanfe diagnose``."""
    from ident.measured import read_measured
    from ident.time_records import is_time_record, read_time_record

    paths = [str(p) for p in paths]
    if not paths:
        raise InputError("no input file")
    if any(is_time_record(p) for p in paths):
        from ident.free_decay_table import free_decay_table
        if len(paths) > 1:
            raise InputError(f"{paths[1]}: one free-decay record at a time")
        return free_decay_table(read_time_record(paths[0], reference=reference),
                                band=band, **(decay_options or {}))
    frf = [is_frf_file(p) for p in paths]
    if not any(frf):
        if len(paths) > 1:
            raise InputError(f"{paths[1]}: one measured-data table at a time (or the FRF "
                             "files of one series)")
        return read_measured(paths[0])
    if not all(frf):
        raise InputError(f"{paths[frf.index(False)]}: not an FRF file (the other files are): "
                         "give either one measured-data table or the FRF files of a series")
    sets = read_series_sets(paths, excitation, control, run_order, reference, test)
    fits = identify_series(sets, band=band, n_modes=n_modes, quantity=quantity,
                           options=options, progress=progress,
                           amplitude_refit=amplitude_refit)
    return series_table(fits)
