"""The example outputs of README.md and docs/*.md are what the commands print
(docs/examples.py).

Runs every example not marked ``slow`` (``gl`` ones only where off-screen rendering
works) in a scratch folder and compares with the pages, ignoring only timings and the
scratch folder's path. On drift: ``python docs/examples.py`` rewrites the pages.
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


def test_another_cpu_class_compares_words_and_layout_not_digits():
    """On a CPU of another vector class than the pages' (docs/examples.py), the digits
    may move by round-off; the words, the verdicts and the number of lines may not."""
    examples = _examples()
    page = ["chi   -0.637463  -0.679425 .. -0.595501   determined / fitted from -0.5574",
            "    1       0.00  rigid-body                 -   7.21e-14"]
    other = ["chi   -0.637464  -0.679426 .. -0.595502   determined / fitted from -0.5574",
             "    1       0.00  rigid-body                 -  -2.08e-13"]
    assert examples.normalized(page) != examples.normalized(other)
    assert examples.masked(page) == examples.masked(other)
    renamed = [page[0].replace("determined", "open"), page[1]]
    assert examples.masked(page) != examples.masked(renamed)
    assert examples.masked(page) != examples.masked(page[:1])
