"""Does a level given as stepped sine look like a random test? The numbers it rests on.

A series read without its test type (or labelled ``stepped-sine``) is identified as a
stepped sine: each level's ``response_amplitude`` is then the mode's amplitude at
resonance, not its RMS, and the abscissa of the estimator changes meaning.
:func:`random_evidence` collects what a level's file shows of an averaged (random)
estimate, :func:`series_warning` makes one line of it for the series.

The evidence, per level:

1. **A coherence column** (``coherence``): an ordinary coherence belongs to an averaged
   estimate (one record of a stepped sine per line has none); its median and minimum
   are reported (a random test's coherence dips at the resonance: leakage, the joint's
   distortion).
2. **The drive spectrum** (``force_psd``, else the ``force`` column): an autospectrum
   averaged over ``n`` records scatters from line to line as a chi-square variable of
   ``2 n`` degrees of freedom, ``std(ln G) ~ 1/sqrt(n)`` (Bendat & Piersol 2010,
   Ch. 8, the normalized random error of an autospectrum), about a trend that a flat
   random drive keeps level over the band; a stepped sine's force is measured line by line under a controller and is smooth
   (the project's synthetic series: 0.1 % in amplitude, 0.2 % in ``ln G``). The scatter
   is that of ``ln G`` from line to line (:func:`spectrum_scatter`; ``G = force^2``
   for the ``force`` column, an amplitude), the trend the 5-95 % spread of its running
   median over the band (dB). A Welch estimate (Hann, 50 % overlap: neighbouring
   lines share data) scatters by about ``0.64 / sqrt(n)`` (measured: 0.12 at 29
   averages). Averaged when the scatter exceeds :data:`AVERAGED_SCATTER` (0.02: ``n``
   below ~1000; an analyser averages 10-300, scatter 0.04-0.2; the project's synthetic
   stepped sines measure 0.0015-0.0034, under force and response control) and the
   trend is within :data:`FLAT_DB` (a response-controlled sine's force dips by the
   resonance: 12 dB in the synthetic series, more on a lightly damped rig).
3. **The FRF's line noise** (:func:`ident.random_frf.random_signature` without the
   coherence): uniform across lines, as an H1's, where a stepped sine's follows the
   response.

Every verdict the tests check (tests/test_random_evidence.py) rests on a threshold a
factor 5 or more from the value measured (scatter 0.12 random, <= 0.0034 stepped sine;
trend 0.7-0.9 dB random against 10), so none turns on round-off.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from ident.random_frf import random_signature

#: Line-to-line scatter of ln G (:func:`spectrum_scatter`) above which it is averaged.
AVERAGED_SCATTER = 0.02
#: Scatter of a Welch autospectrum (Hann, 50 % overlap) times sqrt(averages), measured
#: on the simulated random levels of benchmarks/bench_random_chi.py (0.12 at 29).
WELCH_SCATTER = 0.64
#: Largest 5-95 % spread (dB) of the drive spectrum's trend over the band called flat.
FLAT_DB = 10.0
#: Fewest lines the spectrum test needs.
MIN_LINES = 16
#: Text the warnings of this module start with (per level) or contain (the series).
GIVEN_AS = "given as stepped sine"


@dataclass
class RandomEvidence:
    """What one level's file shows of a random test (module doc).

    Attributes
    ----------
    coherence_median, coherence_min : of the ``coherence`` column, or None.
    spectrum : "force_psd", "force" or None (the drive spectrum judged).
    scatter : std of ln G about its running median (None without a spectrum).
    averages : ``(WELCH_SCATTER / scatter)^2``, the Welch averages such a scatter takes.
    trend_db : 5-95 % spread of the spectrum's running median over the band, dB.
    noise : the line-noise line of :func:`ident.random_frf.random_signature` or None.
    """

    coherence_median: float | None = None
    coherence_min: float | None = None
    spectrum: str | None = None
    scatter: float | None = None
    averages: float | None = None
    trend_db: float | None = None
    noise: str | None = None

    @property
    def averaged_spectrum(self) -> bool:
        return (self.scatter is not None and self.scatter > AVERAGED_SCATTER
                and self.trend_db <= FLAT_DB)

    @property
    def looks_random(self) -> bool:
        return (self.coherence_median is not None or self.averaged_spectrum
                or self.noise is not None)

    def line(self) -> str:
        """The numbers, one line (no newline)."""
        parts = []
        if self.coherence_median is not None:
            parts.append(f"coherence column (median {self.coherence_median:.5f}, "
                         f"min {self.coherence_min:.4f})")
        if self.averaged_spectrum:
            parts.append(f"{self.spectrum} flat over the band (trend {self.trend_db:.1f} dB) "
                         f"with the line-to-line scatter of an average (ln G "
                         f"{self.scatter:.3f}, as ~{self.averages:.0f} Welch averages; "
                         f"a stepped sine's below {AVERAGED_SCATTER})")
        if self.noise is not None:
            parts.append(self.noise)
        return "; ".join(parts)


def spectrum_scatter(freq_hz, spectrum) -> tuple[float, float]:
    """``(line-to-line scatter of ln G, 5-95 % spread of its running median in dB)`` of
    an autospectrum ``G`` (> 0) at the lines ``freq_hz`` (module doc, item 2).

    The scatter is robust to a trend and to a few lines of a resonance dip: the median
    absolute deviation of the second difference ``d_k = ln G_k - (ln G_(k-1) +
    ln G_(k+1)) / 2`` (std ``sqrt(3/2)`` times that of independent lines), as a std."""
    g = np.log(np.asarray(spectrum, float))
    d = g[1:-1] - 0.5 * (g[:-2] + g[2:])
    scatter = 1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(1.5)
    trend = median_filter(g, size=max(9, (g.size // 20) | 1), mode="nearest")
    lo, hi = np.percentile(trend, [5.0, 95.0])
    return float(scatter), float(10.0 / np.log(10.0) * (hi - lo))


def random_evidence(s, modes=(), quantity: str = "receptance") -> RandomEvidence:
    """The evidence (module doc) of one FRF set ``s`` (:class:`ident.frf_files.FRFSet`),
    ``modes`` its identified modes (``pole``, ``shape``) for the line-noise test."""
    ev = RandomEvidence()
    if s.coherence is not None:
        ev.coherence_median = float(np.median(s.coherence))
        ev.coherence_min = float(np.min(s.coherence))
    for name, power in (("force_psd", 1.0), ("force", 2.0)):
        spec = getattr(s, name)
        if spec is not None and spec.size >= MIN_LINES and np.all(spec > 0):
            ev.spectrum = name
            ev.scatter, ev.trend_db = spectrum_scatter(s.freq_hz, spec ** power)
            ev.averages = (WELCH_SCATTER / max(ev.scatter, 1e-12)) ** 2
            break
    ev.noise = random_signature(s.freq_hz, s.frf, modes, quantity)
    return ev


def series_warning(evidence: list) -> str | None:
    """One line for a series whose levels (``evidence``: a :class:`RandomEvidence` or
    None per level, None for a level stated random) look random, else None."""
    judged = [e for e in evidence if e is not None]
    hits = [e for e in judged if e.looks_random]
    if not hits:
        return None

    def median(name):
        v = [getattr(e, name) for e in hits if getattr(e, name) is not None]
        return float(np.median(v)) if v else None

    typical = RandomEvidence(median("coherence_median"), median("coherence_min"),
                             next((e.spectrum for e in hits if e.averaged_spectrum), None),
                             median("scatter"), median("averages"), median("trend_db"),
                             next((e.noise for e in hits if e.noise), None))
    if not any(e.averaged_spectrum for e in hits):
        typical.scatter = None
    return (f"FRF series: {GIVEN_AS}, but {len(hits)} of {len(judged)} levels look like "
            f"a random test (medians over those levels: {typical.line()}): give --test "
            "random (or '# test = random') if it was one")
