# relightnet set-up: every target creates or reuses .venv, installs pinned
# versions, fills the Anny cache once, then runs.
#
# Override the torch wheel on a CUDA machine, e.g.
#   make test TORCH_SPEC="torch==2.13.0 --index-url https://download.pytorch.org/whl/cu128"
# and run the kernel tests (SH, rasterizer, renderer, PRT bounces) on the GPU with
#   make test PYTEST_ARGS="--device cuda"          (also: --dtype float64)
# PYTEST_ARGS defaults to --device cuda when the installed torch sees a CUDA device.
PYTHON      ?= python3
VENV        ?= .venv
TORCH_SPEC  ?= torch==2.13.0
CACHE_DIR   ?= $(CURDIR)/.cache
export ANNY_CACHE_DIR ?= $(CACHE_DIR)/anny
export MPLBACKEND = Agg

PY  := $(VENV)/bin/python
PIP := $(VENV)/bin/python -m pip
# Where the kernel tests run: the GPU when torch sees one (checked when `make test` runs).
PYTEST_ARGS ?= $$($(PY) -c "import torch; print('--device cuda' if torch.cuda.is_available() else '')")

.PHONY: demo test test-fast lint bench bench-deps setup clean-venv system-deps

setup: $(CACHE_DIR)/.sysdeps $(CACHE_DIR)/.sysdeps-browser $(VENV)/.installed $(ANNY_CACHE_DIR)/.filled

demo: setup
	$(VENV)/bin/relightnet demo --out out/demo

# The whole suite, naming its 25 slowest tests at the end (the CI log shows where the time goes).
test: setup
	$(PY) -m pytest -q tests --durations=25 $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing" >&2; exit 1; fi; exit $$rc

# The quick loop: everything but the tests marked slow, ray, browser or blender (a few minutes on 2 cores).
FAST_MARKERS ?= not slow and not ray and not browser and not blender
test-fast: setup
	$(PY) -m pytest -q tests -m "$(FAST_MARKERS)" $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing" >&2; exit 1; fi; exit $$rc

lint: setup
	$(VENV)/bin/ruff check .

bench: setup bench-deps
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

# System packages. The core needs none; Mitsuba 3 (the path-tracing reference and an
# optional ray engine) needs LLVM 19 (with LLVM 15 it crashes). Installed once, with apt.
LLVM_LIB := /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
export DRJIT_LIBLLVM_PATH ?= $(LLVM_LIB)
system-deps: $(CACHE_DIR)/.sysdeps $(CACHE_DIR)/.sysdeps-browser

$(CACHE_DIR)/.sysdeps:
	mkdir -p $(CACHE_DIR)
	if [ ! -e $(LLVM_LIB) ]; then \
	  SUDO=$$( [ "$$(id -u)" -eq 0 ] || echo sudo ); \
	  $$SUDO apt-get update -q && $$SUDO apt-get install -y -q libllvm19; \
	fi
	touch $@

# The app's browser test (tests/app/test_ui.py) drives Debian's headless Chromium through Selenium.
$(CACHE_DIR)/.sysdeps-browser:
	mkdir -p $(CACHE_DIR)
	if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then \
	  SUDO=$$( [ "$$(id -u)" -eq 0 ] || echo sudo ); \
	  $$SUDO apt-get update -q && $$SUDO apt-get install -y -q chromium chromium-driver; \
	fi
	touch $@

# Peers of the benchmarks (not needed by the library or the tests).
bench-deps: $(VENV)/.installed
	SUDO=$$( [ "$$(id -u)" -eq 0 ] || echo sudo ); \
	$$SUDO apt-get update -q && $$SUDO apt-get install -y -q libegl1 libegl-mesa0 libgl1-mesa-dri libgles2
	$(PIP) install -q moderngl==5.13.0

$(VENV)/.installed: pyproject.toml requirements.lock requirements-blender.lock
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	# torch first and alone: the pinned CPU wheel unless TORCH_SPEC says otherwise,
	# so nothing later can pull an unpinned multi-GB CUDA build.
	$(PIP) install -q $(TORCH_SPEC)
	$(PIP) install -q -r requirements.lock
	# The Blender bridge's bpy (~370 MB wheel): its tests are part of the suite. --no-deps:
	# bpy 5.0.1 declares numpy<2 but runs with the pinned numpy 2 (the bridge's tests check it).
	$(PIP) install -q --no-deps -r requirements-blender.lock
	$(PIP) install -q --no-deps -e .
	touch $@

# Anny's first build writes ~800 MB of precomputed data; do it once here.
$(ANNY_CACHE_DIR)/.filled: $(VENV)/.installed
	mkdir -p $(ANNY_CACHE_DIR)
	$(PY) -m relightnet.body.cache
	touch $@

clean-venv:
	rm -rf $(VENV)
