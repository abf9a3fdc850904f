# Quick start: `make run` trains LILI on Point Mass with a small default; `make test` runs the suite.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
INTERACTIONS ?= 300

.PHONY: venv dev run test lint bench clean

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

QUICK := runs/quickstart
# A second `make run` continues (or just re-reports) the same run instead of refusing to overwrite it.
RESUME = $(if $(wildcard $(QUICK)/PointMass-v0/lili/seed_0/metrics.csv),--resume,)

run: venv
	$(BIN)/lili train point-mass --algo lili --seed 0 --interactions $(INTERACTIONS) --out $(QUICK) $(RESUME)
	$(BIN)/lili report $(QUICK) --out $(QUICK)/report

test: dev
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest -q

bench: dev
	$(BIN)/pip install -q -e '.[bench]'
	$(BIN)/python benchmarks/update_speed.py

clean:
	rm -rf $(VENV) runs .pytest_cache
