"""Amplitude-dependent modal data in memory: one entry per (mode, level).

The table of ``docs/formats/measured-data.md`` as arrays; :mod:`ident.measured` reads and
writes it as CSV, :mod:`ident.tracking` builds it from identified levels. SI units:
``omega2`` in rad^2/s^2, ``zeta`` as a fraction.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

#: Test types of ``docs/formats/measured-data.md`` ("Other test types").
TESTS = ("stepped-sine", "random", "free-decay")


@dataclass
class MeasuredData:
    """Amplitude-dependent modal data, one entry per (mode, level), in file order.

    Attributes
    ----------
    level, mode, run_order : ndarray of int
    excitation : ndarray of float
        Excitation amplitude (unit proportional to force).
    omega2 : ndarray of float
        Undamped natural frequency squared, rad^2/s^2.
    zeta : ndarray of float
        Damping ratio (fraction).
    response_amplitude : ndarray of float or None
        Response amplitude at resonance, or None if the file has no such column.
    omega2_std, zeta_std : ndarray of float or None
        Standard uncertainties of ``omega2`` (rad^2/s^2) and ``zeta`` from the
        identification, or None.
    control : ndarray of str
        ``"force"`` or ``"response"`` per entry (what the level held constant).
    test : ndarray of str
        ``"stepped-sine"`` (default), ``"random"`` or ``"free-decay"`` per entry
        (:data:`TESTS`; ``docs/formats/measured-data.md``, "Other test types").
    extra : dict[str, ndarray]
        ``x_*`` annotation columns: float arrays where every value is numeric, else
        str arrays.
    warnings : list[str]
        Non-fatal findings (percent-looking zeta, non-constant excitation ratios).
    line : ndarray of int
        1-based line number of each entry in the source file (0 if not from a file).
    source : str
        The file name the data came from ("" if built in memory).
    rig_repeatability : tuple or None
        What the user states of the rig's run-to-run repeatability: (relative sd of the
        natural frequency, relative sd of the damping ratio, degrees of freedom of that
        statement); None: the judge assumes a typical rig
        (:data:`inverse.judge.prior.RIG_REPEATABILITY`); zeros: assume nothing.
    """

    level: np.ndarray
    excitation: np.ndarray
    omega2: np.ndarray
    zeta: np.ndarray
    mode: np.ndarray
    run_order: np.ndarray
    response_amplitude: np.ndarray | None = None
    omega2_std: np.ndarray | None = None
    zeta_std: np.ndarray | None = None
    control: np.ndarray | None = None
    test: np.ndarray | None = None
    extra: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    line: np.ndarray | None = None
    source: str = ""
    rig_repeatability: tuple | None = None

    def __post_init__(self):
        self.level = np.asarray(self.level, dtype=int)
        n = self.level.size
        self.excitation = np.asarray(self.excitation, dtype=float)
        self.omega2 = np.asarray(self.omega2, dtype=float)
        self.zeta = np.asarray(self.zeta, dtype=float)
        self.mode = np.asarray(self.mode, dtype=int) if self.mode is not None else np.ones(n, int)
        self.run_order = (np.asarray(self.run_order, dtype=int)
                          if self.run_order is not None else self.level.copy())
        for name in ("response_amplitude", "omega2_std", "zeta_std"):
            if getattr(self, name) is not None:
                setattr(self, name, np.asarray(getattr(self, name), dtype=float))
        self.control = (np.full(n, "force") if self.control is None
                        else np.asarray(self.control, dtype=str))
        self.test = (np.full(n, "stepped-sine") if self.test is None
                     else np.asarray(self.test, dtype=str))
        self.line = np.zeros(n, int) if self.line is None else np.asarray(self.line, dtype=int)
        self.extra = {k: np.asarray(v) for k, v in self.extra.items()}
        arrays = [self.excitation, self.omega2, self.zeta, self.mode, self.run_order,
                  self.line, self.control, self.test, *self.extra.values()]
        arrays += [a for a in (self.response_amplitude, self.omega2_std, self.zeta_std)
                   if a is not None]
        if any(a.shape != (n,) for a in arrays):
            raise ValueError("MeasuredData: all columns must be 1-D arrays of equal length")

    def __len__(self) -> int:
        return int(self.level.size)

    @property
    def modes(self) -> np.ndarray:
        """Sorted distinct mode labels."""
        return np.unique(self.mode)

    @property
    def omega_hz(self) -> np.ndarray:
        """Undamped natural frequency sqrt(omega2)/(2 pi), Hz."""
        return np.sqrt(self.omega2) / (2.0 * np.pi)

    @property
    def response_controlled(self) -> bool:
        """True when every entry held a constant response amplitude (``control``)."""
        return bool(len(self)) and bool(np.all(self.control == "response"))

    @property
    def response_abscissa(self) -> bool:
        """True when the response amplitude is the abscissa of every entry: response
        control, a random test (the response RMS) or a free decay (the envelope)."""
        return bool(len(self)) and self.response_amplitude is not None and bool(np.all(
            (self.control == "response") | np.isin(self.test, ("random", "free-decay"))))

    @property
    def held_amplitude(self) -> np.ndarray:
        """The abscissa of the estimator and the diagnosis: ``response_amplitude`` when
        :attr:`response_abscissa`, else ``excitation``."""
        return self.response_amplitude if self.response_abscissa else self.excitation

    @property
    def resonant_amplitude(self) -> np.ndarray:
        """The abscissa on which the diagnosis and its noise model order the levels:
        the held response amplitude when :attr:`response_abscissa`, else
        ``excitation / (zeta omega^2)``, proportional to the resonant modal amplitude
        (paper eq. 31 at ``omega = omega_n``: ``|q| = phi^T f / (2 zeta omega_n^2)``)."""
        if self.response_abscissa:
            return np.asarray(self.response_amplitude, float)
        return self.excitation / (self.zeta * self.omega2)

    @property
    def identified_at_peak(self) -> np.ndarray | None:
        """Rows identified at their level's peak amplitude (a finite ``x_omega2_slope``,
        :mod:`ident.amplitude_poles`, ``--amplitude-refit``), or None without that
        column."""
        col = self.extra.get("x_omega2_slope")
        if col is None:
            return None

        def finite(v):
            try:
                return bool(np.isfinite(float(v)))
            except ValueError:
                return False
        return np.array([finite(v) for v in col])

    def take(self, index) -> "MeasuredData":
        """Entries selected by an index or boolean mask (warnings are kept)."""
        index = np.asarray(index)

        def opt(a):
            return None if a is None else a[index]

        return replace(
            self, level=self.level[index], excitation=self.excitation[index],
            omega2=self.omega2[index], zeta=self.zeta[index], mode=self.mode[index],
            run_order=self.run_order[index], response_amplitude=opt(self.response_amplitude),
            omega2_std=opt(self.omega2_std), zeta_std=opt(self.zeta_std),
            control=self.control[index], test=self.test[index],
            extra={k: v[index] for k, v in self.extra.items()}, line=self.line[index],
            warnings=list(self.warnings))

    @classmethod
    def concatenate(cls, parts: list) -> "MeasuredData":
        """One table of the entries of ``parts`` in order (e.g. one mode each); a column
        only some parts have is left out (``extra``: the columns all have)."""
        def cat(name):
            cols = [getattr(p, name) for p in parts]
            return None if any(c is None for c in cols) else np.concatenate(cols)

        keys = set.intersection(*(set(p.extra) for p in parts))
        return cls(**{n: cat(n) for n in ("level", "excitation", "omega2", "zeta", "mode",
                                          "run_order", "response_amplitude", "omega2_std",
                                          "zeta_std", "control", "test", "line")},
                   extra={k: np.concatenate([p.extra[k] for p in parts]) for k in sorted(keys)},
                   warnings=[w for p in parts for w in p.warnings])

    def for_mode(self, m: int) -> "MeasuredData":
        """Entries of mode ``m`` sorted by level (repeats by run order); ValueError if
        the mode is absent."""
        idx = np.flatnonzero(self.mode == int(m))
        if idx.size == 0:
            raise ValueError(f"mode {m} not in data (modes: {', '.join(map(str, self.modes))})")
        return self.take(idx[np.lexsort((self.run_order[idx], self.level[idx]))])


def mean_per_level(d: MeasuredData) -> tuple[MeasuredData, str | None]:
    """One mode's repeats (rows sharing a level) averaged per level: omega2, zeta,
    excitation and response amplitude by their mean, the identification stds of a mean
    ``sqrt(sum sd^2) / n``, run order and line of the first run. Returns the table and a
    note saying what was averaged (None without repeats). ``d``: one mode sorted by level
    and run order (:meth:`MeasuredData.for_mode`)."""
    levels, start, count = np.unique(d.level, return_index=True, return_counts=True)
    if levels.size == d.level.size:
        return d, None
    inv = np.unique(d.level, return_inverse=True)[1]

    def mean(a):
        return None if a is None else np.bincount(inv, a) / count

    def sd(a):
        return None if a is None else np.sqrt(np.bincount(inv, a**2)) / count

    out = d.take(start)
    out = replace(out, excitation=mean(d.excitation), omega2=mean(d.omega2),
                  zeta=mean(d.zeta), response_amplitude=mean(d.response_amplitude),
                  omega2_std=sd(d.omega2_std), zeta_std=sd(d.zeta_std))
    rep = levels[count > 1]
    return out, (f"repeats averaged per level: {d.level.size} rows -> {levels.size} "
                 f"levels (level{'s' if rep.size > 1 else ''} "
                 f"{', '.join(map(str, rep))} repeated)")


def annotation_warnings(data: MeasuredData) -> list[str]:
    """The ``x_warning`` annotations of a table as warnings, one per non-empty entry:
    ``"<source>: level L, mode M: <text>"`` (identification warnings written by
    :func:`ident.series.series_table`, kept through a CSV round trip)."""
    text = data.extra.get("x_warning")
    if text is None:
        return []
    src = data.source or "data"
    return [f"{src}: level {lv}, mode {m}: {t}"
            for lv, m, t in zip(data.level, data.mode, np.asarray(text, dtype=str))
            if t.strip() and t.strip().lower() != "nan"]
