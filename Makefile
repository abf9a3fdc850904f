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

run: venv
	$(BIN)/lili train point-mass --algo lili --seed 0 --interactions $(INTERACTIONS) --out runs/quickstart
	$(BIN)/lili report runs/quickstart --out runs/quickstart/report

test: dev
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest -q

bench: dev
	$(BIN)/pip install -q -e '.[bench]'
	$(BIN)/python benchmarks/update_speed.py

clean:
	rm -rf $(VENV) runs .pytest_cache
