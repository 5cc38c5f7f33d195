"""A simulated ring-down identified like a measured one, against the backbone and the
response-controlled virtual test.

Three routes to the mode's frequency and damping ratio against the drive-point
amplitude (first-harmonic displacement amplitude, m), all on the joints the integration
uses (:attr:`casefile.jointed.NonlinearCase.time_path`: the Jenkins banks, or a law
without banks through its exact first harmonic):

* ``ringdown``: the free-decay record (:mod:`cases.ringdown_study`) identified by the
  measured-record route (:mod:`ident.free_decay`: band-pass, Hilbert envelope and phase,
  end effects trimmed), rows whose amplitude lies between ``lo`` and ``hi`` times the
  start amplitude (default 5 % and 80 %: the compared window; the trimmed ends are
  stated);
* ``epmc``: the nonlinear mode (:func:`fe.epmc.epmc_backbone`, Krack 2015) normalized at
  the drive point, continued over the record's amplitudes and read at each row's
  amplitude (monotone cubic in log amplitude, :meth:`fe.backbone.Backbone.at`);
* ``response``: response-controlled stepped sine (:func:`cases.backbone_routes.response_route`,
  LSCF per level) holding ``n_response`` drive-point amplitudes spread over the window.

Each route's relative deviation from the EPMC backbone at the same amplitude is
reported: ``f/f_epmc - 1`` and ``zeta/zeta_epmc - 1``. SI units: Hz, m.
"""
from __future__ import annotations

import numpy as np

from cases.backbone_routes import response_route
from fe.epmc import epmc_backbone

__all__ = ["identify_record", "compare_ringdown", "comparison_rows"]

#: Acceptance of issue 21: ring-down against EPMC at every amplitude of the window.
FREQUENCY_TARGET = 1e-4
ZETA_TARGET = 0.02
#: The analysed part of a simulated record (:func:`identify_record`) and its rows.
ANALYSED_FLOOR = 1e-2
TAIL_PERIODS = 10
ROWS = 40


def identify_record(path, mode_hz: float, floor: float = ANALYSED_FLOOR,
                    n_rows: int = ROWS) -> dict:
    """Identify the free-decay CSV ``path`` in the band ``mode_hz`` +-30 % as a measured
    record (:func:`ident.free_decay_table.identify_free_decay`: band-pass or modal
    filter over the points, Hilbert track, end effects trimmed, ``n_rows`` amplitude
    bins). A simulated record has no noise floor: it is analysed until the reference
    point's displacement in the band last exceeds ``floor`` times its largest value, plus
    :data:`TAIL_PERIODS` periods (below that the record holds the other modes and
    round-off, not the mode's decay). Returns the spec's ``table``
    (:class:`ident.modal_data.MeasuredData`), its rows along the decay as arrays
    ``amplitude`` (m, reference point), ``frequency_hz``, ``zeta``, ``zeta_std`` and
    ``notes`` (what was cut and trimmed, the warnings)."""
    from ident.free_decay_table import free_decay_table, identify_free_decay
    from ident.time_records import TimeRecord, read_time_record

    from scipy import signal

    full = read_time_record(path)
    band = (0.7 * mode_hz, 1.3 * mode_hz)
    sos = signal.butter(4, band, btype="bandpass", fs=full.sample_rate, output="sos")
    x = np.abs(signal.sosfiltfilt(sos, full.signals[:, full.reference]))   # the mode's band
    last = int(np.flatnonzero(x >= floor * x.max())[-1])
    end = min(full.time_s.size, last + int(TAIL_PERIODS * full.sample_rate / mode_hz) + 1)
    record = TimeRecord(full.time_s[:end], full.signals[:end], full.points, full.quantity,
                        full.reference, full.source)
    res = identify_free_decay(record, band, n_rows)
    table = free_decay_table(record, band, n_rows, result=res)
    order = np.argsort(table.run_order)                     # along the decay
    return {"table": table, "amplitude": table.response_amplitude[order],
            "frequency_hz": np.sqrt(table.omega2[order]) / (2 * np.pi),
            "zeta": table.zeta[order], "zeta_std": table.zeta_std[order],
            "method": "Hilbert envelope and phase (ident.free_decay)",
            "notes": [f"analysed: the first {record.time_s[-1]:.4g} s of {full.time_s[-1]:.4g} "
                      f"s (until the reference displacement in the band falls below "
                      f"{floor:g} x its largest value, + {TAIL_PERIODS} periods)",
                      res.trim_statement,
                      *res.warnings]}


def compare_ringdown(case, ident: dict, start_amplitude: float, lo: float = 0.05,
                     hi: float = 0.8, n_response: int = 4, n_backbone: int = 40,
                     progress: bool = False, store=None) -> dict:
    """The three routes on the window ``[lo, hi]`` x ``start_amplitude`` (m, drive point;
    module docstring).

    Parameters
    ----------
    case : cases.nonlinear_case.NonlinearCase
    ident : dict of :func:`identify_record`.
    start_amplitude : float, the record's first identified amplitude (m).
    n_response : int, held amplitudes of the response-controlled test (0: skipped).
    store : directory of the response-controlled campaign (resumable), or None.

    Returns
    -------
    dict with ``rows`` (ring-down rows in the window and the nearest one beyond each of
    its ends, so that they bracket it, with the backbone's values and the
    deviations), ``response`` (the virtual test's levels likewise), ``max_deviation``,
    ``targets`` and ``met``.
    """
    amp = np.asarray(ident["amplitude"], dtype=float)
    f_rd = np.asarray(ident["frequency_hz"], dtype=float)
    z_rd = np.asarray(ident["zeta"], dtype=float)
    win = (amp >= lo * start_amplitude) & (amp <= hi * start_amplitude)
    for beyond, nearest in ((amp > hi * start_amplitude, np.argmin),
                            (amp < lo * start_amplitude, np.argmax)):
        if beyond.any():        # the nearest row outside: the compared rows bracket the window
            win[np.flatnonzero(beyond)[nearest(amp[beyond])]] = True
    if win.sum() < 2:
        raise ValueError(f"the identified record has fewer than 2 rows between {lo:g} and "
                         f"{hi:g} x the start amplitude")
    a_lo, a_hi = float(amp[win].min()), float(amp[win].max())
    grid = np.geomspace(0.9 * a_lo, 1.1 * a_hi, n_backbone)
    path = case.time_path              # the joints the integration used
    bb = epmc_backbone(case.model, case.joint_harmonics(path), case.mode, grid,
                       at=case.drive_dof)
    ref = bb.at(amp[win])
    f_bb, z_bb = np.sqrt(ref["omega2"]) / (2 * np.pi), ref["zeta"]
    rows = [{"amplitude_m": float(a), "over_start": float(a / start_amplitude),
             "frequency_hz": float(f), "zeta": float(z), "epmc_frequency_hz": float(fb),
             "epmc_zeta": float(zb), "frequency_deviation": float(f / fb - 1.0),
             "zeta_deviation": float(z / zb - 1.0)}
            for a, f, z, fb, zb in zip(amp[win], f_rd[win], z_rd[win], f_bb, z_bb)]
    response = []
    if n_response > 0:
        held = np.geomspace(a_lo, a_hi, n_response)
        data, _ = response_route(case, held, path=path, progress=progress, store=store)
        ref_r = bb.at(held)
        for i, a in enumerate(held):
            f, fb = float(data.omega_hz[i]), float(np.sqrt(ref_r["omega2"][i]) / (2 * np.pi))
            response.append({"amplitude_m": float(a), "over_start": float(a / start_amplitude),
                             "frequency_hz": f, "zeta": float(data.zeta[i]),
                             "epmc_frequency_hz": fb, "epmc_zeta": float(ref_r["zeta"][i]),
                             "frequency_deviation": f / fb - 1.0,
                             "zeta_deviation": float(data.zeta[i] / ref_r["zeta"][i] - 1.0),
                             "force_N": float(data.excitation[i])})
    dev = {"ringdown": {"frequency": max(abs(r["frequency_deviation"]) for r in rows),
                        "zeta": max(abs(r["zeta_deviation"]) for r in rows)}}
    if response:
        dev["response"] = {"frequency": max(abs(r["frequency_deviation"]) for r in response),
                           "zeta": max(abs(r["zeta_deviation"]) for r in response)}
    met = (dev["ringdown"]["frequency"] <= FREQUENCY_TARGET
           and dev["ringdown"]["zeta"] <= ZETA_TARGET)
    return {"window": {"lo": lo, "hi": hi, "start_amplitude_m": start_amplitude,
                       "rows_in_window": int(win.sum()), "rows_outside": int((~win).sum())},
            "rows": rows, "response": response, "max_deviation": dev,
            "targets": {"frequency": FREQUENCY_TARGET, "zeta": ZETA_TARGET}, "met": bool(met),
            "backbone": {"amplitude_m": bb.amplitude, "frequency_hz": bb.frequency_hz,
                         "zeta": bb.zeta, "path": path, "points": len(bb)}}


def comparison_rows(cmp: dict) -> list[str]:
    """The comparison as a plain-text table."""
    out = [" route      amplitude_m  /start    f_Hz          f_EPMC_Hz     df/f        "
           "zeta_%     zeta_EPMC_%  dzeta/zeta"]
    for route, rows in (("ringdown", cmp["rows"]), ("response", cmp["response"])):
        for r in rows:
            out.append(f" {route:9s}  {r['amplitude_m']:11.4e}  {r['over_start']:6.3f}  "
                       f"{r['frequency_hz']:12.6f}  {r['epmc_frequency_hz']:12.6f}  "
                       f"{r['frequency_deviation']:+10.2e}  {100 * r['zeta']:9.6f}  "
                       f"{100 * r['epmc_zeta']:9.6f}  {r['zeta_deviation']:+10.2e}")
    return out
