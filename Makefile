# Set-up and entry points. `make demo` and `make test` work on a fresh machine:
# they create .venv, install posture_id with its pinned CPU torch, then run.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test test-fast lint bench bodies clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# torch first, pinned, so that nothing later resolves a CUDA build from the registry.
	$(BIN)/pip install --quiet "torch==2.13.0"
	$(BIN)/pip install --quiet -e ".[dev]"
	@if $(BIN)/pip list 2>/dev/null | grep -qi '^nvidia-'; then \
	  echo "error: CUDA packages were installed on a CPU set-up; see README" >&2; exit 1; fi
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/posture-id body urdf/tip_default.urdf
	$(BIN)/posture-id simulate --out demo/trial.csv --plot demo/trial.png
	@echo "demo: wrote demo/trial.csv and demo/trial.png"

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check posture_id tests benchmarks
	$(BIN)/lint-imports

bodies: $(STAMP)
	for r in talos g1 human; do $(BIN)/posture-id body --from-robot $$r --out urdf/$${r}_tip.urdf > /dev/null; done
	$(BIN)/posture-id body --default-tip --out urdf/tip_default.urdf > /dev/null

bench: $(STAMP)
	$(BIN)/python benchmarks/simulation.py

clean:
	rm -rf $(VENV) demo
