# Quick start: `make demo` and `make test` (both create .venv on first use).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
# Kernel cache shared by every run and test of this checkout (compile once, reuse).
export WARP_CACHE_PATH ?= $(CURDIR)/.warp_cache

.PHONY: demo test test-slow test-extremes venv lint clean

$(BIN)/tightknot: pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[fem,pardiso,test,distributed,tables]"
	touch $(BIN)/tightknot

venv: $(BIN)/tightknot

demo: venv
	$(BIN)/tightknot demo --out runs/demo --overwrite

# CI and `make test`: everything but the long checks (marked slow: the FEM's fine meshes),
# on two workers (pytest-xdist), the cores CI has: Warp's CPU kernels run on one thread.
# The 25 slowest tests are listed at the end: CI has 20 minutes on two cores.
test: venv
	$(BIN)/python -m pytest -q -m "not slow" -n 2 --durations=25

test-slow: venv
	$(BIN)/python -m pytest -q -m slow

# The whole numerical-stability stress suite (CI runs only its fast subset).
test-extremes: venv
	$(BIN)/python -m pytest -q tests/extremes --run-extremes

lint: venv
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) .warp_cache runs
