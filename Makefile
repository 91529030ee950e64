# The two commands a fresh machine needs: `make run` and `make test`.
# Both set up idempotently first (system packages, .venv, the project).

VENV := .venv
BIN := $(VENV)/bin
PYTEST := $(BIN)/pytest -p no:cacheprovider

.PHONY: setup run test test-slow bench

setup:
	@bash scripts/setup.sh

run: setup
	$(BIN)/hfpbd up

test: setup
	$(PYTEST) -m "not slow"

# End-to-end runs of the whole system; CI runs them after `make test`.
test-slow: setup
	$(PYTEST) -m slow; status=$$?; [ $$status -eq 0 ] || [ $$status -eq 5 ]

bench: setup
	@for what in bus nlu sim perception executor speech tasks; do echo "== hfpbd bench $$what"; $(BIN)/hfpbd bench $$what || exit 1; done
