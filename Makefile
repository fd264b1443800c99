# Two entry points for a fresh clone (Python 3.10+ and pip are all that is needed):
#   make run    installs everything into .venv and runs the main job
#   make test   installs everything into .venv and runs the CI test suite
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
# torch is pinned in the same pip command so that pip takes the small CPU build.
PIP_PKGS := -e ".[agents,dev,ray]" torch==2.13.0
export MUJOCO_GL ?= egl
export OMP_NUM_THREADS ?= 1

.PHONY: install run test lint bench clean

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.installed: $(BIN)/activate pyproject.toml
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet $(PIP_PKGS)
	bash .ci/system-gl.sh
	touch $@

install: $(VENV)/.installed

run: install
	$(BIN)/rdmp-gym main --out runs/main

test: install
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

bench: install
	$(BIN)/python benchmarks/bench_fidelity.py
	$(BIN)/python benchmarks/bench_speed.py
	$(BIN)/python benchmarks/bench_env.py
	$(BIN)/python benchmarks/bench_throughput.py
	$(BIN)/python benchmarks/bench_agents.py
	$(BIN)/python benchmarks/bench_memory.py

clean:
	rm -rf $(VENV) runs figures
