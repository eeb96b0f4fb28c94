# Two commands on a fresh machine with Python >= 3.10, pip and make:
#   make run    -> one grasp plan on the embedded default scene
#   make test   -> the test suite
# Both create (or reuse) the project's virtual environment in .venv.
# The venv's interpreter. Debian's /usr/bin/python3 (built with PGO and LTO) runs the benchmarks
# 1.1-1.3x faster than a default source build such as pyenv's, but speeds py_trees up more than the
# EOS controller (bench_controller's ratio goes 0.14x -> 0.18x); see docs/benchmarks.md.
# Choose it with: make clean && make PYTHON=/usr/bin/python3 test
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-all lint format docs bench clean chromium

$(STAMP): pyproject.toml setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/eos plan

test: $(STAMP) chromium
	$(PY) -m pytest -q

# Headless Chromium for the 3-D view's browser tests (tests/view): installed with apt-get when
# missing and running as root; elsewhere those tests are skipped and say why.
chromium:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || \
	if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing chromium (apt-get) for the browser tests"; \
		{ apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } || \
			echo "could not install chromium: the browser tests will be skipped"; \
	else \
		echo "chromium is missing and cannot be installed here (needs root and apt-get): the browser tests will be skipped"; \
	fi

test-all: $(STAMP) chromium
	$(PY) -m pytest -q -m "slow or not slow"

# lint: ruff's rules, ruff's formatting (checked, not applied: `make format` applies it) and mypy
lint: $(STAMP)
	$(VENV)/bin/ruff check eos_svc tests benchmarks clients docs/api.py
	$(VENV)/bin/ruff format --check eos_svc tests benchmarks clients docs/api.py
	$(VENV)/bin/mypy

format: $(STAMP)
	$(VENV)/bin/ruff format eos_svc tests benchmarks clients docs/api.py

# The API reference, built from the docstrings into build/api/ (not kept in git) by pdoc;
# any pdoc warning (e.g. an annotation it cannot resolve) fails the build.
docs: $(STAMP)
	$(PY) docs/api.py build/api

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache build
