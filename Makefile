# Two entry points, both self-contained from a fresh clone:
#   make run   -> create .venv if missing, install, run the main job on the default case
#   make test  -> same set-up, then the whole test suite (pytest-xdist: one worker per
#                 core, at most 4; each worker holds ~0.6 GB)
# Both install the tested set of versions: constraints.txt pins every package of the
# environment (pip, setuptools and wheel included, `==` each; the build of the editable
# install is pinned to the same file). Those pins are what CI tests. `make lock` rebuilds
# them from a fresh venv resolved against pyproject.toml's open ranges (docs/setup.md).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
PINS   := constraints.txt
LOCK_VENV := .venv-lock

.PHONY: run test install lock clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml $(PINS)
	$(BIN)/python -m pip install --quiet -c $(PINS) pip setuptools wheel
	$(BIN)/python -m pip install --quiet -c $(PINS) --build-constraint $(PINS) -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/iwanfe loop --case double-beam --out results/double-beam

test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4

# Refresh the pins: a fresh venv, the newest versions pyproject.toml allows, then its
# `pip freeze --all` (less the editable iwanfe) becomes constraints.txt. Run `make test`
# after it and commit constraints.txt with the results.
lock:
	rm -rf $(LOCK_VENV)
	$(PYTHON) -m venv $(LOCK_VENV)
	$(LOCK_VENV)/bin/python -m pip install --quiet --upgrade pip setuptools wheel
	$(LOCK_VENV)/bin/python -m pip install --quiet -e ".[test]"
	{ echo "# The tested set of versions: make install/run/test install exactly these"; \
	  echo "# (pip install -c constraints.txt). Written by 'make lock' on Python \
	$$($(LOCK_VENV)/bin/python -c 'import platform; print(platform.python_version())'); \
	do not edit by hand."; \
	  $(LOCK_VENV)/bin/python -m pip freeze --all --exclude-editable; } > $(PINS).new
	mv $(PINS).new $(PINS)
	rm -rf $(LOCK_VENV)

clean:
	rm -rf $(VENV) $(LOCK_VENV) results .pytest_cache build dist *.egg-info
