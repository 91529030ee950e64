# The two commands a fresh machine needs: `make run` and `make test`.
# Both set up idempotently first (system packages, .venv, the project).

VENV := .venv
BIN := $(VENV)/bin
PYTEST := $(BIN)/pytest -p no:cacheprovider

.PHONY: setup run lint test test-unit test-slow bench

setup:
	@bash scripts/setup.sh

run: setup
	$(BIN)/hfpbd up

# ruff (lint and format) and mypy (the config in pyproject.toml names what it checks)
lint: setup
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

test: lint
	$(PYTEST) -m "not slow"

# The tests that start no process, no simulator and no terminal app: under a minute.
test-unit: setup
	$(PYTEST) -m unit

# End-to-end runs of the whole system; CI runs them after `make test`.
test-slow: setup
	$(PYTEST) -m slow; status=$$?; [ $$status -eq 0 ] || [ $$status -eq 5 ]

bench: setup
	@for what in bus nlu sim perception executor manipulation skills fuzz speech speech-latency tasks; do echo "== hfpbd bench $$what"; $(BIN)/hfpbd bench $$what || exit 1; done
