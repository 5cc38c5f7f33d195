"""The paper's double-beam measurements (Tables 3-6) and their consistency checks.

The paper (Section 4) prints, for the second mode of its Fig. 7 (about 252 Hz), ten
stepped-sine levels driven at 5 mV .. 2.56 V (doubling), as

* Table 3: loss of omega^2 between successive levels (rad^2/s^2, 2 decimals),
* Table 4: omega^2 per level (rad^2/s^2, 6 significant digits, i.e. +/- 5),
* Table 5: growth of zeta between successive levels (percent, 4 significant digits),
* Table 6: zeta per level (percent, 4 decimals),

each with the paper's estimates for levels 8-10 and an error column. The tables are
not mutually consistent. The estimator works on differences, and Tables 3 and 5 are
printed with 10 to 1000 times finer resolution than the differences of Tables 4 and
6, so the shipped file ``cases/data/double_beam_measured.csv`` is built as

    omega2_v = T4[1] - sum_{u=2..v} T3[u-1 -> u],   zeta_v = T6[1] + sum T5   (fraction)

which reproduces Tables 3 and 5 exactly; the printed absolute values of Tables 4 and
6 are kept as the annotation columns ``x_table4_omega2`` and ``x_table6_zeta``.
:func:`check_paper_tables` lists every place where the printed numbers disagree
beyond their printed rounding (interval arithmetic: each printed number is
``value +/- half a unit in its last printed digit``; a derived number carries the
propagated half-widths).

Run ``python -m cases.paper_data`` to print the checks, ``--write`` to rebuild the
shipped file. The tables are transcribed here so that the package does not need the
paper files at run time; the tests compare them with ``shared/data/paper/``.
"""
from __future__ import annotations

import argparse
import csv
import io
import sys
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

import numpy as np

from ident.measured import MeasuredData, write_measured

DATA_FILE = Path(__file__).resolve().parent / "data" / "double_beam_measured.csv"

#: Mode label written in the shipped file: the paper's "second mode in the figure"
#: (Fig. 7, band 50-450 Hz), about 252 Hz. It is a label, not an FE mode number.
MODE_LABEL = 2
#: Drive voltage of level 1 (V); each level doubles it: 5 mV .. 2.56 V (paper Sec. 4).
FIRST_VOLTAGE = 0.005
VOLTAGE_RATIO = 2.0
#: The paper's published identification (Sec. 4): chi, |kappa1| B, R, B.
PUBLISHED = {"chi": -0.37366, "kappa1_B": 29.431, "R": 3.5431e5, "B": 2.787e-4}
PUBLISHED_TEXT = {"chi": "-0.37366", "kappa1_B": "29.431", "R": "3.5431e5", "B": "2.787e-4"}

# Transcribed from the paper (identical to shared/data/paper/table{3,4,5,6}_*.csv).
TABLE_TEXT = {
    "table3": """from_experiment,to_experiment,measured_rad2_s2,paper_estimated_rad2_s2,paper_error_percent
1,2,8.18,,
2,3,40.45,,
3,4,-23.11,,
4,5,39.92,,
5,6,59.58,,
6,7,148.04,,
7,8,114.08,110.71,-2.94
8,9,206.67,180.91,-12.47
9,10,304.64,283.82,-6.83
""",
    "table4": """experiment,measured_rad2_s2,paper_estimated_rad2_s2,paper_error_percent
1,2.50677e6,,
2,2.50676e6,,
3,2.50672e6,,
4,2.50674e6,,
5,2.50670e6,,
6,2.50671e6,,
7,2.50656e6,,
8,2.50645e6,2.50646e6,4e-4
9,2.50624e6,2.50641e6,6.5e-3
10,2.50594e6,2.50631e6,1.5e-2
""",
    "table5": """from_experiment,to_experiment,measured_percent,paper_estimated_percent,paper_error_percent
1,2,6.072e-4,,
2,3,-4.385e-4,,
3,4,2.457e-4,,
4,5,1.167e-3,,
5,6,2.118e-3,,
6,7,3.804e-3,,
7,8,4.122e-3,4.012e-3,-2.67
8,9,5.569e-3,5.329e-3,-4.30
9,10,9.583e-3,8.280e-3,-13.60
""",
    "table6": """experiment,measured_percent,paper_estimated_percent,paper_error_percent
1,1.2780,,
2,1.2795,,
3,1.2791,,
4,1.2793,,
5,1.2805,,
6,1.2830,,
7,1.2864,,
8,1.2905,1.2888,-1.3e-1
9,1.2961,1.2940,-1.6e-1
10,1.3056,1.3021,-2.7e-1
""",
}


def half_ulp(text: str) -> float:
    """Half a unit in the last printed digit of a number as printed.

    ``half_ulp("2.50677e6") == 5.0``, ``half_ulp("6.072e-4") == 5e-8``,
    ``half_ulp("-2.94") == 0.005``.
    """
    exponent = Decimal(text.strip()).as_tuple().exponent
    return 0.5 * 10.0 ** int(exponent)


@dataclass(frozen=True)
class PrintedColumn:
    """One column of a printed table: values and their rounding half-widths.

    Missing entries (the paper's ``*``) are NaN in both arrays.
    """

    value: np.ndarray
    half_width: np.ndarray


def read_table(text: str) -> dict[str, PrintedColumn]:
    """Parse a printed table (CSV text) into columns of (value, half-width)."""
    rows = list(csv.DictReader(io.StringIO(text)))
    out = {}
    for name in rows[0]:
        texts = [r[name].strip() for r in rows]
        value = np.array([float(t) if t else np.nan for t in texts])
        width = np.array([half_ulp(t) if t else np.nan for t in texts])
        out[name] = PrintedColumn(value, width)
    return out


def paper_tables() -> dict[str, dict[str, PrintedColumn]]:
    """Tables 3-6 as printed, keyed ``table3`` .. ``table6``."""
    return {k: read_table(v) for k, v in TABLE_TEXT.items()}


def build_measured() -> MeasuredData:
    """The shipped double-beam data set (see module docstring for the construction).

    Returns
    -------
    MeasuredData
        Levels 1-10, excitation = drive voltage ``0.005 * 2**(level-1)`` V, ``omega2``
        (rad^2/s^2) from Table 4 level 1 minus the cumulative Table 3 losses, ``zeta``
        (fraction) from Table 6 level 1 plus the cumulative Table 5 growths, mode label
        :data:`MODE_LABEL`; annotations ``x_table4_omega2`` (rad^2/s^2) and
        ``x_table6_zeta`` (fraction) hold the printed absolute values.
    """
    t = paper_tables()
    level = np.arange(1, 11)
    loss = t["table3"]["measured_rad2_s2"].value
    growth = t["table5"]["measured_percent"].value
    omega2_printed = t["table4"]["measured_rad2_s2"].value
    zeta_printed = t["table6"]["measured_percent"].value / 100.0
    omega2 = omega2_printed[0] - np.concatenate(([0.0], np.cumsum(loss)))
    zeta = zeta_printed[0] + np.concatenate(([0.0], np.cumsum(growth))) / 100.0
    # round away float noise of the cumulative sums (printed resolution is far coarser)
    omega2 = np.round(omega2, 6)
    zeta = np.round(zeta, 12)
    return MeasuredData(
        level=level,
        excitation=FIRST_VOLTAGE * VOLTAGE_RATIO ** (level - 1),
        omega2=omega2, zeta=zeta, mode=np.full(level.size, MODE_LABEL),
        run_order=level.copy(),
        extra={"x_table4_omega2": omega2_printed, "x_table6_zeta": np.round(zeta_printed, 8)},
        source="paper Tables 3-6")


def write_shipped(path=DATA_FILE) -> Path:
    """Write :func:`build_measured` to ``path`` (default: the shipped file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_measured(path, build_measured())
    return path


# --------------------------------------------------------------------------- checks


@dataclass(frozen=True)
class TableCheck:
    """One comparison of a printed number with the same quantity derived otherwise.

    ``ok`` is True when ``|printed - derived| <= tolerance`` (the sum of the rounding
    half-widths of everything involved). Units are those of ``quantity``.
    """

    group: str
    where: str
    quantity: str
    printed: float
    derived: float
    tolerance: float

    @property
    def difference(self) -> float:
        return self.printed - self.derived

    @property
    def ok(self) -> bool:
        return abs(self.difference) <= self.tolerance * (1 + 1e-9)

    def message(self) -> str:
        return (f"{self.where}: {self.quantity} printed {self.printed:.6g}, derived "
                f"{self.derived:.6g} (difference {self.difference:.3g}, rounding allows "
                f"{self.tolerance:.2g})")


def _ratio_percent(est, meas):
    """100 (est - meas)/meas with the propagated half-width, for (value, width) pairs."""
    (e, he), (m, hm) = est, meas
    value = 100.0 * (e - m) / m
    width = 100.0 * (he / abs(m) + abs(e) * hm / m ** 2)
    return value, width


def check_paper_tables() -> list[TableCheck]:
    """Every cross-check between the printed Tables 3-6 and the published parameters.

    Groups:

    ``measured``
        Table 3 vs successive differences of Table 4 (loss of omega^2), Table 5 vs
        successive differences of Table 6, and the cumulative sums of Tables 3 / 5
        from level 1 vs the absolute values of Tables 4 / 6.
    ``error column``
        each printed error percent vs ``100 (estimated - measured)/measured``.
    ``estimates``
        the estimated differences (Tables 3, 5) vs the differences of the estimated
        absolute values (Tables 4, 6); for level 8 the measured level 7 is the base.
    ``model``
        the estimated differences must form a geometric sequence of ratio
        ``2**(chi+1)`` (paper eqs. 34, 43, 46 with constant z = 2, published chi);
        ``|kappa1(R, chi)| B`` (paper eq. A15) vs the published ``|kappa1| B``.

    Returns
    -------
    list[TableCheck]
        All checks, passing or not; ``[c for c in checks if not c.ok]`` are the
        disagreements beyond printed rounding.
    """
    t = paper_tables()
    return (_measured_checks(t) + _cumulative_checks(t) + _error_column_checks(t)
            + _estimate_checks(t) + _model_checks(t))


def _pair(col: PrintedColumn, i: int) -> tuple[float, float]:
    """Entry ``i`` of a printed column as (value, half-width)."""
    return col.value[i], col.half_width[i]


def _measured_checks(t: dict[str, dict[str, PrintedColumn]]) -> list[TableCheck]:
    """Tables 3 / 5 against the successive differences of Tables 4 / 6."""
    m3, m4 = t["table3"]["measured_rad2_s2"], t["table4"]["measured_rad2_s2"]
    m5, m6 = t["table5"]["measured_percent"], t["table6"]["measured_percent"]
    checks: list[TableCheck] = []
    for i in range(9):
        a, b = i + 1, i + 2
        checks.append(TableCheck(
            "measured", f"Table 3 vs Table 4, level {a}->{b}", "loss of omega^2 [rad^2/s^2]",
            m3.value[i], m4.value[i] - m4.value[i + 1],
            m3.half_width[i] + m4.half_width[i] + m4.half_width[i + 1]))
        checks.append(TableCheck(
            "measured", f"Table 5 vs Table 6, level {a}->{b}", "growth of zeta [%]",
            m5.value[i], m6.value[i + 1] - m6.value[i],
            m5.half_width[i] + m6.half_width[i] + m6.half_width[i + 1]))
    return checks


def _cumulative_checks(t: dict[str, dict[str, PrintedColumn]]) -> list[TableCheck]:
    """Tables 4 / 6 against level 1 and the cumulative sums of Tables 3 / 5."""
    m3, m4 = t["table3"]["measured_rad2_s2"], t["table4"]["measured_rad2_s2"]
    m5, m6 = t["table5"]["measured_percent"], t["table6"]["measured_percent"]
    cum3 = np.cumsum(m3.value)
    cum3w = np.cumsum(m3.half_width)
    cum5 = np.cumsum(m5.value)
    cum5w = np.cumsum(m5.half_width)
    checks: list[TableCheck] = []
    for i in range(1, 10):
        checks.append(TableCheck(
            "measured", f"Table 4 level {i + 1} vs Table 4 level 1 - sum of Table 3",
            "omega^2 [rad^2/s^2]", m4.value[i], m4.value[0] - cum3[i - 1],
            m4.half_width[i] + m4.half_width[0] + cum3w[i - 1]))
        checks.append(TableCheck(
            "measured", f"Table 6 level {i + 1} vs Table 6 level 1 + sum of Table 5",
            "zeta [%]", m6.value[i], m6.value[0] + cum5[i - 1],
            m6.half_width[i] + m6.half_width[0] + cum5w[i - 1]))
    return checks


def _error_column_checks(t: dict[str, dict[str, PrintedColumn]]) -> list[TableCheck]:
    """Each printed error percent against ``100 (estimated - measured)/measured``."""
    checks: list[TableCheck] = []
    for name, tab, meas, est in (
            ("Table 3", t["table3"], "measured_rad2_s2", "paper_estimated_rad2_s2"),
            ("Table 4", t["table4"], "measured_rad2_s2", "paper_estimated_rad2_s2"),
            ("Table 5", t["table5"], "measured_percent", "paper_estimated_percent"),
            ("Table 6", t["table6"], "measured_percent", "paper_estimated_percent")):
        err = tab["paper_error_percent"]
        for i in np.flatnonzero(np.isfinite(err.value)):
            value, width = _ratio_percent(_pair(tab[est], i), _pair(tab[meas], i))
            row = (f"level {i + 1}" if name in ("Table 4", "Table 6")
                   else f"level {i + 1}->{i + 2}")
            checks.append(TableCheck(
                "error column", f"{name} error column, {row}", "error [%]",
                err.value[i], value, err.half_width[i] + width))
    return checks


def _estimate_checks(t: dict[str, dict[str, PrintedColumn]]) -> list[TableCheck]:
    """Estimated differences against the differences of the estimated absolute values."""
    m4, m6 = t["table4"]["measured_rad2_s2"], t["table6"]["measured_percent"]
    e3, e4 = t["table3"]["paper_estimated_rad2_s2"], t["table4"]["paper_estimated_rad2_s2"]
    e5, e6 = t["table5"]["paper_estimated_percent"], t["table6"]["paper_estimated_percent"]
    checks: list[TableCheck] = []
    for i in range(6, 9):  # pairs 7->8, 8->9, 9->10
        base4 = (m4 if i == 6 else e4)
        base6 = (m6 if i == 6 else e6)
        label = "measured" if i == 6 else "estimated"
        checks.append(TableCheck(
            "estimates", f"Table 3 estimate {i + 1}->{i + 2} vs Table 4 ({label} {i + 1} "
            f"- estimated {i + 2})", "loss of omega^2 [rad^2/s^2]",
            e3.value[i], base4.value[i] - e4.value[i + 1],
            e3.half_width[i] + base4.half_width[i] + e4.half_width[i + 1]))
        checks.append(TableCheck(
            "estimates", f"Table 5 estimate {i + 1}->{i + 2} vs Table 6 (estimated {i + 2} "
            f"- {label} {i + 1})", "growth of zeta [%]",
            e5.value[i], e6.value[i + 1] - base6.value[i],
            e5.half_width[i] + e6.half_width[i + 1] + base6.half_width[i]))
    return checks


def _model_checks(t: dict[str, dict[str, PrintedColumn]]) -> list[TableCheck]:
    """Geometric sequences of ratio ``z**(chi+1)`` and the published ``|kappa1| B``."""
    from joints.describing import kappa1

    e3, e5 = t["table3"]["paper_estimated_rad2_s2"], t["table5"]["paper_estimated_percent"]
    checks: list[TableCheck] = []
    ratio = VOLTAGE_RATIO ** (PUBLISHED["chi"] + 1.0)
    for name, col in (("Table 3", e3), ("Table 5", e5)):
        for i in (7, 8):
            v, w = col.value[i], col.half_width[i]
            p, pw = col.value[i - 1], col.half_width[i - 1]
            checks.append(TableCheck(
                "model", f"{name} estimates, ratio ({i + 1}->{i + 2})/({i}->{i + 1})",
                "ratio of successive estimated differences (2^(chi+1) = "
                f"{ratio:.4f} for the published chi)", v / p, ratio,
                w / abs(p) + abs(v) * pw / p ** 2))
    hw = {k: half_ulp(v) for k, v in PUBLISHED_TEXT.items()}
    k1r = abs(kappa1(1.0, PUBLISHED["chi"]))
    derived = k1r * PUBLISHED["R"] * PUBLISHED["B"]
    checks.append(TableCheck(
        "model", "published |kappa1|B vs |kappa1(R, chi)| B (eq. A15)", "|kappa1| B [1/s^2]",
        PUBLISHED["kappa1_B"], derived,
        hw["kappa1_B"] + derived * (hw["R"] / PUBLISHED["R"] + hw["B"] / PUBLISHED["B"])))
    return checks


def disagreements() -> list[TableCheck]:
    """The checks of :func:`check_paper_tables` that fail."""
    return [c for c in check_paper_tables() if not c.ok]


def main(argv: list[str] | None = None) -> int:
    """``python -m cases.paper_data [--write [PATH]] [--all]``."""
    parser = argparse.ArgumentParser(
        prog="python -m cases.paper_data",
        description="Consistency checks of the paper's Tables 3-6; --write rebuilds the "
                    "shipped measured-data file.")
    parser.add_argument("--write", nargs="?", const=str(DATA_FILE), default=None,
                        metavar="PATH", help=f"write the data file (default {DATA_FILE})")
    parser.add_argument("--all", action="store_true", help="list passing checks too")
    args = parser.parse_args(argv)
    if args.write:
        print(f"wrote {write_shipped(args.write)}")
    checks = check_paper_tables()
    bad = [c for c in checks if not c.ok]
    print(f"{len(checks)} checks, {len(bad)} disagreements beyond printed rounding")
    for c in checks if args.all else bad:
        print(("  ok   " if c.ok else "  FAIL ") + f"[{c.group}] " + c.message())
    return 0


if __name__ == "__main__":
    sys.exit(main())
