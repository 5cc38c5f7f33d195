"""``iwanfe identify RECORD``: a free-decay time record, identified along its decay.

Called by :mod:`cli.commands.identify` when a FILE is a time record
(:func:`ident.time_records.is_time_record`); prints both methods per row, the trimmed
ends, the warnings (one line each), and writes the measured-data rows with ``--out``.
"""
from __future__ import annotations

import numpy as np

from cli import validate
from ident.free_decay_table import free_decay_table, identify_free_decay
from ident.time_records import read_time_record
from runs.jsonio import print_json


def run_free_decay(args) -> int:
    """Identify one free-decay record (module doc)."""
    if len(args.files) > 1:
        raise ValueError(f"{args.files[1]}: one free-decay record at a time")
    if args.band is not None:
        validate.band(args.band)
    if args.out:
        validate.output_file(args.out, "--out", (".csv",))
    record = read_time_record(args.files[0], reference=args.reference)
    result = identify_free_decay(record, band=args.band, n_rows=args.rows)
    table = free_decay_table(record, result=result)
    if args.out:
        from ident.measured import write_measured
        write_measured(args.out, table)
    if args.json:
        print_json(_as_json(args.files[0], record, result, table))
        return 0
    _print(args.files[0], record, result, table)
    if args.out:
        print(f"wrote {args.out}")
    return 0


def _print(name, record, res, table):
    iso = res.isolated
    print(f"{name}: free decay, {len(record.points)} point(s), {record.quantity}, "
          f"amplitude at point {record.points[record.reference]}, band "
          f"{iso.band_hz[0]:.4g}-{iso.band_hz[1]:.4g} Hz")
    print(f"  {res.trim_statement}")
    print("  rows (measured; std = fit std with the transient-loop allowance; peaks = the "
          "peak/zero-crossing check):")
    print(f"  {'level':>5} {'amplitude':>11} {'f_hilbert_hz':>13} {'f_peaks_hz':>12} "
          f"{'zeta_hilbert':>12} {'std':>8} {'zeta_peaks':>10} {'cycles':>6} {'SNR_dB':>6}")
    x = table.extra
    for i in range(len(table)):
        print(f"  {table.level[i]:5d} {table.response_amplitude[i]:11.4g} "
              f"{x['x_frequency_hz'][i]:13.6f} {x['x_frequency_hz_peaks'][i]:12.6f} "
              f"{table.zeta[i]:12.6f} {table.zeta_std[i]:8.2g} {x['x_zeta_peaks'][i]:10.6f} "
              f"{x['x_cycles'][i]:6.1f} {x['x_snr_db'][i]:6.1f}")
    for w in table.warnings[1:]:
        print(f"warning: {w}")


def _as_json(name, record, res, table):
    x = table.extra
    return {
        "file": name, "test": "free-decay", "quantity": record.quantity,
        "reference": record.points[record.reference], "band_hz": list(res.isolated.band_hz),
        "trim": res.trim_statement, "trim_s": list(res.isolated.trim_s),
        "warnings": table.warnings[1:],
        "levels": [{"level": table.level[i], "response_amplitude": table.response_amplitude[i],
                    "omega2": table.omega2[i], "omega2_std": table.omega2_std[i],
                    "zeta": table.zeta[i], "zeta_std": table.zeta_std[i],
                    "run_order": table.run_order[i], "frequency_hz": x["x_frequency_hz"][i],
                    "frequency_hz_peaks": x["x_frequency_hz_peaks"][i],
                    "zeta_peaks": x["x_zeta_peaks"][i], "snr_db": x["x_snr_db"][i],
                    "cycles": x["x_cycles"][i],
                    "warnings": [w for w in str(x["x_warning"][i]).split(" | ") if w]}
                   for i in np.argsort(table.level)]}
