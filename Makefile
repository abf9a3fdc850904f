# Quick start: `make run` trains LILI and SAC on Driving (2D) and reports them beside the paper;
# `make test` runs the suite.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: venv dev run test test-slow lint bench clean

$(BIN)/lili: pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e .
	@touch $@

venv: $(BIN)/lili

$(VENV)/.dev: $(BIN)/lili
	$(BIN)/pip install -q -e '.[dev]'
	@touch $@

dev: $(VENV)/.dev

# LILI against SAC on Driving (2D), two runs side by side (lili.experiments.presets: quickstart).
# A second `make run` skips the finished runs and only writes the report again.
run: venv
	$(BIN)/lili reproduce quickstart --out runs

# Two pytest workers (pytest-xdist), each running a whole test file (or test class) at a time,
# so a file's module fixtures are made once and the two cores of the CI machine both work; the
# files in the order tests/conftest.py gives them (the longest first), not xdist's own.
PYTEST_PAR := -n 2 --dist loadscope --no-loadscope-reorder

test: dev
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest -q $(PYTEST_PAR)

# The tests marked slow (long learning runs, every agent on every env, the costlier variants).
test-slow: dev
	$(BIN)/python -m pytest -q -m slow $(PYTEST_PAR)

bench: dev
	$(BIN)/pip install -q -e '.[bench]'
	$(BIN)/python benchmarks/update_speed.py

clean:
	rm -rf $(VENV) runs .pytest_cache
