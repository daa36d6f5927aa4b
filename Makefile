# Two commands matter on a fresh clone: `make sweep` and `make test`.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# Compiled numba code goes to the one documented cache folder, as outside make (docs/solver.md:
# $EHD_CACHE_DIR, else $NUMBA_CACHE_DIR, else $XDG_CACHE_HOME/ehd-collision or
# ~/.cache/ehd-collision; `ehd info` prints it). Nothing here overrides it.
# One scene per core: threaded BLAS only slows the small dense solves (docs/solver.md).
# `ehd` sets these itself (pipeline/environment.py); exported here for the benchmarks and tests,
# which import `solver` directly.
export OMP_NUM_THREADS := 1
export OPENBLAS_NUM_THREADS := 1
export MKL_NUM_THREADS := 1

.PHONY: install test test-install test-memory test-dem sweep quick figures bench bench-validation bench-sweep bench-accuracy bench-experiments clean-cache clean

# solver/result.py: the package version is its SOLVER_VERSION (pyproject: dynamic), so a new
# solver version reinstalls and the installed metadata never goes stale
$(STAMP): pyproject.toml setup.py solver/result.py
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; set PYTHON=/path/to/python3.11"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e .[test]
	touch $(STAMP)

install: $(STAMP)

# The install tests (marker "install": a fresh venv and an empty compile cache each, about
# 80 s apiece) run in make test-install, which .ci/run calls, so make test stays under 10 minutes
# Both tiers run on TEST_WORKERS processes (pytest-xdist; each loads the compiled cache, or on a
# cold cache compiles it, about 600 MiB at its peak); make test TEST_WORKERS=0 runs in one process
TEST_WORKERS ?= 2
test: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) -m "not install and not memory"

# The inner loop: the suite without the tests marked slow (tests/conftest.py SLOW), under 2 minutes
.PHONY: test-fast
test-fast: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) -m "not install and not memory and not slow"

# pip install of the clone into a fresh venv, then the README's first commands from an empty
# folder (tests/install_from_pip.py), and the install tests of the compile cache's folder (a few
# minutes: each fresh install compiles the solver). The two files run side by side, one per
# worker (--dist loadfile: install_from_pip.py's tests share one install)
test-install: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile -m install tests/install_from_pip.py \
	  tests/test_environment.py

# No result reads memory the solver never wrote: the scenes of tests/poison/scenes.py solved
# as installed and with numba's fresh arrays filled with NaN and with 1e306 bytes must agree bit
# for bit (tests/test_memory.py; compiles the solver twice more, a few minutes)
test-memory: $(STAMP)
	$(PY) -m pytest -q -m memory tests/test_memory.py

# The exported DEM snippets run in the real programs (tests/test_dem_programs.py, ~30 s): the
# Debian packages liggghts (3.8.0) and yade (2023.02a) are installed when missing, with
# apt-get install -y (root and apt-get only); without them their tests skip, each saying why.
DEM_PROGRAMS := liggghts yade
test-dem: $(STAMP)
	@missing=""; for p in $(DEM_PROGRAMS); do command -v $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "test-dem: installing$$missing (apt-get install -y)"; \
	    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq$$missing >/dev/null; } \
	      || echo "test-dem: apt-get could not install$$missing: their tests skip"; \
	  else echo "test-dem:$$missing not installed and no root apt-get here: their tests skip"; fi; \
	fi
	$(PY) -m pytest -q -ra tests/test_dem_programs.py

# The sweep's figures are drawn also when some scenes failed (exit 3: failures are masked in
# them); make still reports the sweep's exit code. Exit 2 (bad input) draws nothing.
sweep: $(STAMP)
	@rc=0; $(VENV)/bin/ehd sweep sweeps/paper.toml || rc=$$?; \
	if [ $$rc -eq 0 ] || [ $$rc -eq 3 ]; then \
	  $(VENV)/bin/ehd figures results/paper.zarr --out figures || exit $$?; fi; exit $$rc

# 24 small scenes: local threads start in a fraction of the time a process cluster needs
quick: $(STAMP)
	@rc=0; $(VENV)/bin/ehd sweep sweeps/quick.toml --executor threads || rc=$$?; \
	if [ $$rc -eq 0 ] || [ $$rc -eq 3 ]; then \
	  $(VENV)/bin/ehd figures results/quick.zarr --out figures/quick || exit $$?; fi; exit $$rc

figures: $(STAMP)
	$(VENV)/bin/ehd figures results/paper.zarr --out figures
	$(VENV)/bin/ehd paper-figures --out figures

# The speed suite (benchmarks/README.md): start-up and solver figures of this checkout against a
# baseline commit, alternated in one run; the report says which figures moved beyond the spread of
# their rounds -> benchmarks/speed.md/.json. BASELINE=REF (default: the commit of speed.json).
BASELINE ?=
bench: $(STAMP)
	$(PY) benchmarks/suite.py $(if $(BASELINE),--baseline $(BASELINE))

# The validation studies (accuracy per preset, cavitation, piezoviscous film, experiments): tens
# of minutes; each also has its own script (benchmarks/README.md, "Validation")
bench-validation: $(STAMP)
	$(PY) benchmarks/bench_accuracy.py
	$(PY) benchmarks/bench_extrapolation.py
	$(PY) benchmarks/bench_moved.py
	$(PY) benchmarks/bench_cavitation.py
	$(PY) benchmarks/bench_piezoviscous.py
	$(PY) benchmarks/bench_trajectory.py
	$(PY) benchmarks/bench_experiments.py
	$(PY) benchmarks/bench_threshold_budget.py

# The measured Gondret trajectories against the computed ones (bench_trajectory.py, whose json
# the experiments' figure reads), then e(St) on the conditions of published sphere-wall
# experiments, per variant of the physics, the correlation shown as a correlation ->
# benchmarks/trajectory.* and experiments.md/.json/.png (~4 min); the energy budget at the
# rebound threshold -> benchmarks/threshold_budget.md (~15 s)
bench-experiments: $(STAMP)
	$(PY) benchmarks/bench_trajectory.py
	$(PY) benchmarks/bench_experiments.py
	$(PY) benchmarks/bench_threshold_budget.py

bench-sweep: $(STAMP)
	$(PY) benchmarks/bench_sweep.py

bench-accuracy: $(STAMP)
	$(PY) benchmarks/bench_accuracy.py
	$(PY) benchmarks/bench_extrapolation.py
	$(PY) benchmarks/bench_moved.py

# The documentation site -> docs/_build/html/index.html (docs/conf.py), warnings as errors. Phony:
# the docs/ folder never makes it "up to date". The docs extra is installed once per venv.
.PHONY: docs
DOCS_STAMP := $(VENV)/.installed-docs
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e .[docs]
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(VENV)/bin/sphinx-build -W --keep-going -q -b html docs docs/_build/html

# the compiled kernels of every solver version (solver-*/ under <cache root>/numba, the root
# resolved as in solver/_jit.py:cache_root), and the project-local folder older versions used
clean-cache:
	rm -rf "$${EHD_CACHE_DIR:-$${NUMBA_CACHE_DIR:-$${XDG_CACHE_HOME:-$$HOME/.cache}/ehd-collision}}/numba" .numba_cache

clean: clean-cache
	rm -rf $(VENV) .pytest_cache
