# Two entry points for a fresh clone (Python 3.10+ and pip are all that is needed):
#   make run    installs everything into .venv and runs the main job
#   make test   installs everything into .venv and runs the CI test suite (`make test-all`: with the slow tests)
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
# .ci/constraints-cpu.txt pins torch to the small CPU build (the agents extra only bounds torch).
PIP_PKGS := -c .ci/constraints-cpu.txt -e ".[agents,dev,ray,docs,panda]"
export MUJOCO_GL ?= egl
export OMP_NUM_THREADS ?= 1
export NO_MKDOCS_2_WARNING ?= 1

.PHONY: install run test test-all docs wheel-check lint bench clean

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.installed: $(BIN)/activate pyproject.toml setup.py .ci/constraints-cpu.txt
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet $(PIP_PKGS)
	bash .ci/system-gl.sh
	touch $@

install: $(VENV)/.installed

# A second `make run` continues the finished run in runs/main (--resume: nothing left to train) and redoes
# the figures and the evaluation instead of refusing to overwrite it.
RUN_OUT   ?= runs/main
RUN_FLAGS ?=
run: install
	$(BIN)/rdmp-gym main --out $(RUN_OUT) $(RUN_FLAGS) $$(test -f $(RUN_OUT)/train/config.json && echo --resume)

# The docs build is strict: a broken link, a missing figure or a renamed function in the API reference fails it.
# pytest runs on every core (pytest-xdist), one test file per worker so that a file's module fixtures are built
# once; PYTEST_JOBS= runs it in one process. `make test` leaves out the tests marked slow (pyproject's addopts),
# `make test-all` runs them too (-m '' overrides the marker filter).
PYTEST_JOBS ?= -n auto --dist loadfile
test: install
	$(BIN)/ruff check .
	$(BIN)/mkdocs build --strict --quiet --site-dir build/site
	$(BIN)/python -m pytest -q $(PYTEST_JOBS)

test-all: install
	$(BIN)/ruff check .
	$(BIN)/mkdocs build --strict --quiet --site-dir build/site
	$(BIN)/python -m pytest -q $(PYTEST_JOBS) -m ''

# The documentation site (MkDocs + mkdocstrings) into site/; open site/index.html.
docs: install
	$(BIN)/mkdocs build --strict --site-dir site

# The packaging check of CI: build the wheel, install it (not editable) in a fresh venv, use it.
wheel-check:
	bash .ci/wheel-check.sh

# Benchmarks write runs/benchmarks/; `make bench BENCH_FLAGS=--save` rewrites the committed benchmarks/results/.
bench: install
	$(BIN)/python benchmarks/bench_fidelity.py $(BENCH_FLAGS)
	$(BIN)/python benchmarks/bench_speed.py $(BENCH_FLAGS)
	$(BIN)/python benchmarks/bench_env.py $(BENCH_FLAGS)
	$(BIN)/python benchmarks/bench_throughput.py $(BENCH_FLAGS)
	$(BIN)/python benchmarks/bench_agents.py $(BENCH_FLAGS)
	$(BIN)/python benchmarks/bench_memory.py $(BENCH_FLAGS)

clean:
	rm -rf $(VENV) runs figures site build
