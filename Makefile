# Two entry points, both self-contained from a fresh clone:
#   make run   -> create .venv if missing, install, run the main job on the default case
#   make test  -> same set-up, then the whole test suite (pytest-xdist: one worker per
#                 core, at most 4; each worker holds ~0.6 GB)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test install clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/iwanfe loop --case double-beam --out results/double-beam

test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4

clean:
	rm -rf $(VENV) results .pytest_cache build dist *.egg-info
