# Self-bootstrapping targets: each creates .venv and installs cistrack into it on first use.
# Two stamps: the demo needs only the base install; tests add the [test] and [dask] extras
# (the study tests run a local Dask cluster).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
BASE_STAMP := $(VENV)/.base-stamp
STAMP := $(VENV)/.installed-stamp
# setuptools prints an informational note ("Editable installation ... be careful with folders
# named like your package") for every editable install of a package-dir mapping such as ours
# (core/ -> cistrack). It is not a problem with the project; keep it out of the demo's output.
PIP_ENV := PYTHONWARNINGS="ignore:Editable installation:UserWarning"

.PHONY: demo test test-all bench clean

$(VENV)/bin/python:
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(BASE_STAMP): pyproject.toml $(VENV)/bin/python
	$(PIP_ENV) $(BIN)/python -m pip install --quiet -e .
	touch $(BASE_STAMP)

# The tests install small plugin packages with --no-build-isolation: they need a recent setuptools.
$(STAMP): pyproject.toml $(BASE_STAMP)
	$(PIP_ENV) $(BIN)/python -m pip install --quiet "setuptools>=77" wheel -e ".[test,dask]"
	touch $(STAMP)

## Set up, then run the built-in default scenario (paper Example 1 with the PGM filter).
demo: $(BASE_STAMP)
	$(BIN)/cistrack run

## Set up, then run the fast test suite (slow end-to-end cases are deselected).
test: $(STAMP)
	$(BIN)/python -m pytest

## Everything, including the slow end-to-end and statistical tests. The viewer test opens a
## recording in headless Chromium (Debian package "chromium"); it is installed here if missing
## and possible, else that test is skipped. The fast suite never needs it.
test-all: $(STAMP)
	command -v chromium >/dev/null 2>&1 || apt-get install -y chromium || \
		echo "chromium not installed: tests/recorders/test_viewer_in_browser.py will be skipped"
	$(BIN)/python -m pytest -m "slow or not slow"

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[benchmark]"
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info runs studies_out
