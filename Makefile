# Two commands on a fresh machine with Python >= 3.10, pip and make:
#   make run    -> one grasp plan on the embedded default scene
#   make test   -> the test suite
# Both create (or reuse) the project's virtual environment in .venv.
# The venv's interpreter: the distribution's CPython when it has venv (Debian builds it with PGO
# and LTO; the benchmarks run 1.1-1.3x faster on it than on a default source build such as pyenv's,
# see docs/benchmarks.md), else the first python3 on PATH. Override: make PYTHON=python3.12 test
PYTHON ?= $(shell /usr/bin/python3 -c 'import sys, venv, ensurepip; sys.exit(sys.version_info < (3, 10))' \
            >/dev/null 2>&1 && echo /usr/bin/python3 || echo python3)
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-all lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/eos plan

test: $(STAMP)
	$(PY) -m pytest -q

test-all: $(STAMP)
	$(PY) -m pytest -q -m "slow or not slow"

lint: $(STAMP)
	$(VENV)/bin/ruff check eos_svc tests benchmarks clients
	$(VENV)/bin/mypy

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
