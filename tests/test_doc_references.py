"""Every repository path a document or docstring names in backquotes or a Markdown link
(``docs/...``, ``cases/...``, ...) exists, and nothing points outside the repository to
the brief's ``shared/`` folder, which a user does not have.

Truth: the file system of the checkout."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: a path in backquotes or a Markdown link target, starting at a top-level folder
PATH = re.compile(r"[`(]((?:docs|cases|ident|inverse|fe|joints|runs|cli|viz|benchmarks|"
                  r"examples|tests)/[A-Za-z0-9_./-]+\.(?:md|py|toml|csv))[`)#]")


def _tracked(suffixes=(".md", ".py")):
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    if out.returncode != 0:          # not a git checkout (an sdist): every file
        return [p for p in ROOT.rglob("*") if p.suffix in suffixes and ".venv" not in p.parts]
    return [ROOT / f for f in out.stdout.split() if Path(f).suffix in suffixes]


def test_named_repository_paths_exist():
    missing = set()
    for f in _tracked():
        for m in PATH.finditer(f.read_text(encoding="utf-8", errors="replace")):
            target = m.group(1).rstrip(".")
            if not (ROOT / target).exists() and "*" not in target:
                missing.add(f"{f.relative_to(ROOT)}: {target}")
    assert not missing, sorted(missing)


def test_the_formats_are_in_the_repository():
    for name in ("case-file", "measured-data", "diagnosis"):
        assert (ROOT / "docs" / "formats" / f"{name}.md").is_file()
    offenders = [str(f.relative_to(ROOT)) for f in _tracked()
                 if "shared/spec" in f.read_text(encoding="utf-8", errors="replace")
                 and f.name != Path(__file__).name and "outside_users" not in f.parts]
    assert not offenders, offenders
