"""The command line names no case: every ``--case`` resolves through
:mod:`cases.registry` (a shipped name or a case file). Any string constant in ``cli/``
(docstrings and help examples aside) that is a shipped case name, or compares with one,
is a defect."""
from __future__ import annotations

import ast
from pathlib import Path

from cases.registry import SHIPPED

ROOT = Path(__file__).resolve().parents[1]
#: Known exceptions, each with its reason; the lead removes them after merging:
KNOWN = {
    # reproduce TARGET names the paper's reproductions (double-beam, lumped), not --case:
    "cli/commands/reproduce.py",
}


def _docstrings(tree) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                ids.add(id(body[0].value))
    return ids


def _case_names_in(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text())
    skip = _docstrings(tree)
    hits = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
            if node.value in SHIPPED:
                hits.append((node.lineno, node.value))
    return hits


def test_cli_holds_no_case_name():
    hits = []
    for path in sorted((ROOT / "cli").rglob("*.py")):
        if str(path.relative_to(ROOT)) not in KNOWN:
            hits += [f"{path.relative_to(ROOT)}:{n}: {v!r}" for n, v in _case_names_in(path)]
    assert not hits, "case names in cli/: " + "; ".join(hits)


def test_the_scan_finds_a_planted_name(tmp_path):
    planted = tmp_path / "probe.py"
    planted.write_text('"""Docstring: --case brb is fine here."""\n'
                       'def f(args):\n    return args.case == "brb"\n')
    assert _case_names_in(planted) == [(3, "brb")]
