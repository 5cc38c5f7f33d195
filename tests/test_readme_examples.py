"""The example outputs of README.md and docs/*.md are what the commands print
(docs/examples.py).

Runs every example not marked ``slow`` (``gl`` ones only where off-screen rendering
works) in a scratch folder and compares with the pages, ignoring only timings and the
scratch folder's path: words and layout exactly, each number within its stated tolerance
(docs/examples.py ``compare``, ``TOLERANCES``), the same on every machine. On drift:
``python docs/examples.py`` rewrites the pages.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@lru_cache(maxsize=1)
def _examples():
    """docs/examples.py as a module, loaded by path (the name ``examples`` is also the
    folder of Python-API scripts; sys.path is left alone)."""
    spec = importlib.util.spec_from_file_location("iwanfe_docs_examples",
                                                  ROOT / "docs" / "examples.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod                   # its dataclasses look themselves up
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_readme_examples_match_the_commands():
    """Each page in its own scratch folder, two pages at a time (the pages share no
    state; the machine has 2 cores)."""
    from concurrent.futures import ThreadPoolExecutor

    def check(page):
        return subprocess.run([sys.executable, str(ROOT / "docs/examples.py"), "--check",
                               "--fast", "--page", str(page)],
                              cwd=ROOT, capture_output=True, text=True, timeout=1200)

    with ThreadPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(check, _examples().pages()))
    for run in runs:
        assert run.returncode == 0, ("README examples drifted (python docs/examples.py "
                                     "rewrites them):\n" + run.stdout[-6000:]
                                     + run.stderr[-2000:])
    assert sum(run.stderr.count("ran ") for run in runs) >= 6    # the examples did run


def test_example_blocks_are_well_formed():
    examples = _examples()
    pages = examples.pages()
    assert ROOT / "README.md" in pages and ROOT / "docs/commands.md" in pages
    found = [ex for page in pages
             for ex in examples.find_examples(page.read_text(encoding="utf-8").split("\n"))]
    assert len(found) >= 12
    assert all(ex.commands for ex in found)
    # every command shown in an example block is run, none is hand-written output
    commands = [c for ex in found for _, c in ex.commands]
    assert any(c.startswith("iwanfe joint") for c in commands)
    assert any(c.startswith("iwanfe uncertainty") for c in commands)
    assert any(c.startswith("python examples/") for c in commands)


def test_readme_is_a_front_page():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    assert "make run" in text and "make test" in text


def test_normalization_ignores_only_timings():
    examples = _examples()

    a = ["wrote m.png: mode 4, 252.00 Hz (thickness x13.3, 1.1 s)", "time: 49.5 s total"]
    b = ["wrote m.png: mode 4, 252.00 Hz (thickness x13.3, 5.6 s)", "time: 50 s total"]
    assert examples.normalized(a) == examples.normalized(b)
    c = ["wrote m.png: mode 4, 252.01 Hz (thickness x13.3, 1.1 s)", "time: 49.5 s total"]
    assert examples.normalized(a) != examples.normalized(c)


def test_numbers_compare_within_their_tolerance_words_exactly():
    """docs/examples.py compares words and layout exactly and each number within its
    tolerance, the same on every machine: round-off in the last digits passes, a moved
    result, a changed word, a line more or less fails."""
    compare = _examples().compare
    page = ["$ iwanfe update --case lap.toml",
            "chi                             -0.637  -0.679 .. -0.596       determined",
            "joint: R~ = 6.819e+07 N/m^(chi+2), phi_max = 0.0003053 m, 363 free DOFs",
            "  macro-slip   w 0.000  dAIC     -4.9  k  9  p    0.22  gain 0.104  not nameable",
            "time: 9.1 s (serial)"]
    same = list(page)
    same[2] = "joint: R~ = 6.82e+07 N/m^(chi+2), phi_max = 0.0003053 m, 363 free DOFs"
    same[4] = "time: 5.1 s (serial)"
    assert compare(page, same) == []             # %g dropped a zero; timings ignored
    # one unit in the last digit (two roundings of one value) and the default rtol 1e-6
    assert compare(["x 9.453291"], ["x 9.453282"]) == []
    assert compare(["x 9.453291"], ["x 9.453271"]) != []
    assert compare(["x 2.60e-06"], ["x 2.61e-06"]) == []
    assert compare(["x 2.60e-06"], ["x 2.62e-06"]) != []
    # a counted integer has no last-digit slack
    assert compare(["363 free DOFs"], ["364 free DOFs"]) != []
    # the held-out gain that moved (0.104 -> 0.115) fails, named with both values
    moved = list(page)
    moved[3] = moved[3].replace("0.104", "0.115")
    (problem,) = compare(page, moved)
    assert "page 0.104, command 0.115" in problem and "tolerance 0.001" in problem
    assert "line 4, number 5" in problem
    # changed words: a verdict, "n/a" for a number, a line less
    assert compare(page, [ln.replace("determined", "not determined") for ln in page])
    assert compare(["rate  1.59  1.73"], ["rate  n/a  1.73"])
    assert compare(page, page[:-2] + page[-1:])
    # spaces collapse (a column widened by a digit is the same layout); numbers still count
    assert compare(["   1    0.5"], ["   1   10.5"]) != []
    assert compare(["   1    0.5"], ["   1     0.5"]) == []


def test_the_stated_per_quantity_tolerances_apply():
    """A rigid-body mode's zero eigenvalue gets an absolute floor (any sign, 1e-13 ..
    1e-9), its elastic neighbours do not; a block's ``rtol=`` raises every number's."""
    examples = _examples()
    compare = examples.compare
    page = ["    1       0.00  rigid-body                 -  -2.08e-13",
            "    3       0.01  rigid-body                 -  -1.51e-09",
            "    4     166.85  bending                    1   3.81e-02"]
    other = ["    1       0.00  rigid-body                 -   7.21e-14",
             "    3       0.00  rigid-body                 -  -6.63e-10",
             "    4     166.85  bending                    1   3.81e-02"]
    assert compare(page, other) == []
    elastic = other[:2] + ["    4     166.85  bending                    1   3.83e-02"]
    (problem,) = compare(page, elastic)
    assert "(default)" in problem and "page 3.81e-02, command 3.83e-02" in problem
    # the rigid-body floors are absolute and stated: a real glue slip is not within them
    assert compare(page[:1], ["    1       0.00  rigid-body                 -   2.00e-05"])
    names = {t.quantity: t for t in examples.TOLERANCES}
    assert names["rigid-body glue slip"].atol == 1e-6
    # every stated tolerance has its reason beside it (a comment) and matches a line
    source = (ROOT / "docs" / "examples.py").read_text(encoding="utf-8")
    table = source[source.index("TOLERANCES = ("):source.index("\n)\n", source.index(
        "TOLERANCES = ("))]
    assert table.count("Tolerance(") == len(examples.TOLERANCES) >= 4
    assert table.count("#") >= len(examples.TOLERANCES) // 2
    # a block's option raises every number's tolerance
    assert compare(["gain 0.104"], ["gain 0.110"]) != []
    assert compare(["gain 0.104"], ["gain 0.110"], {"rtol": "0.1"}) == []
    assert compare(["gain 0.104"], ["gain 0.110"], {"atol": "0.01"}) == []
    assert examples.parse_options("rtol=1e-3 slow") == {"rtol": "1e-3", "slow": True}


def test_near_zero_numbers_need_their_absolute_floor():
    """Without a stated floor a number near zero compares relatively: a sign flip of a
    round-off value fails unless its quantity is in the table."""
    compare = _examples().compare
    assert compare(["residual -2.08e-13"], ["residual 7.21e-14"]) != []
    assert compare(["residual -2.08e-13"], ["residual 7.21e-14"], {"atol": "1e-12"}) == []
    assert compare(["shift +0.00"], ["shift -0.00"]) == []
