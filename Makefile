# Self-bootstrapping targets: each creates .venv and installs cistrack into it on first use.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-stamp

.PHONY: demo test test-all bench clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip setuptools wheel
	$(BIN)/python -m pip install --quiet -e ".[test,dask]"
	touch $(STAMP)

## Set up, then run the built-in default scenario (paper Example 1 with the PGM filter).
demo: $(STAMP)
	$(BIN)/cistrack run

## Set up, then run the fast test suite (slow end-to-end cases are deselected).
test: $(STAMP)
	$(BIN)/python -m pytest

## Everything, including the slow end-to-end and statistical tests.
test-all: $(STAMP)
	$(BIN)/python -m pytest -m "slow or not slow"

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[benchmark]"
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info runs studies_out
