"""When a drift with time can be told from an amplitude effect (one rule for the noise
model, the one-mode diagnosis and the FE level: :func:`inverse.judge.time_separable`).

Truth by construction: a run order whose levels, taken in order of amplitude, come
one after the other in time (however their repeats sit next to them) carries no
information on time that amplitude does not; a repeat run at the other end of the test
does."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from inverse.judge import time_separable


def _orders(levels):
    """Run orders of the rows of ``levels`` (sorted, repeats side by side): descending
    in time with every repeat run right after its level, and the same with the lowest
    level's second run moved to the start of the test."""
    levels = np.asarray(levels)
    rows = np.lexsort((np.arange(levels.size), -levels))
    adjacent = np.empty(levels.size, int)
    adjacent[rows] = np.arange(1, levels.size + 1)
    moved = adjacent + 1
    moved[np.flatnonzero(levels == levels.min())[-1]] = 1
    return adjacent, moved


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_repeat_next_to_its_level_leaves_the_run_order_monotone(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 13))
    twice = [1, int(rng.integers(2, n + 1))]             # the lowest and another level
    levels = np.sort(np.r_[np.arange(1, n + 1), twice])
    adjacent, moved = _orders(levels)
    amplitude = np.exp(np.log(rng.uniform(1.15, 2.0)) * levels)
    for a in (None, amplitude):
        assert not time_separable(levels, adjacent, a)
        assert not time_separable(levels, adjacent.max() + 1 - adjacent, a)   # ascending
        assert time_separable(levels, moved, a)
    assert not time_separable(np.arange(n), np.arange(n))
    assert time_separable(np.r_[np.arange(n), 0], np.arange(n + 1))  # lowest again at the end


def test_the_diagnosis_and_the_fe_level_test_drift_only_where_time_is_separable():
    """A plain series from the independent generator with repeated levels, its rows
    given the two run orders above: thermal drift untested at both levels on the
    first, tested on the second."""
    from feloop.select import untestable
    from synthetic import generate_series
    from inverse.diagnose import diagnose

    rng = np.random.default_rng(7)
    for seed in rng.integers(1, 10**6, 50):
        s = generate_series("none", int(seed))
        if s.truth["n_repeats"] >= 1 and np.unique(s.data.level).size >= 5:
            break
    d = s.data.take(np.lexsort((s.data.run_order, s.data.level)))
    adjacent, moved = _orders(d.level)
    for order, separable in ((adjacent, False), (moved, True)):
        table = replace(d, run_order=order)
        r = diagnose(table)
        assert ("thermal-drift" in r["untestable"]) is not separable, r["untestable"]
        assert ("thermal-drift" in untestable(table)) is not separable
