# relightnet set-up: every target creates or reuses .venv, installs pinned
# versions, fills the Anny cache once, then runs.
#
# Override the torch wheel on a CUDA machine, e.g.
#   make test TORCH_SPEC="torch==2.13.0 --index-url https://download.pytorch.org/whl/cu128"
PYTHON      ?= python3
VENV        ?= .venv
TORCH_SPEC  ?= torch==2.13.0
CACHE_DIR   ?= $(CURDIR)/.cache
export ANNY_CACHE_DIR ?= $(CACHE_DIR)/anny
export MPLBACKEND = Agg

PY  := $(VENV)/bin/python
PIP := $(VENV)/bin/python -m pip

.PHONY: demo test lint bench setup clean-venv system-deps

setup: $(VENV)/.installed $(ANNY_CACHE_DIR)/.filled

demo: setup
	$(VENV)/bin/relightnet demo --out out/demo

test: setup
	$(PY) -m pytest -q tests; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing" >&2; exit 1; fi; exit $$rc

lint: setup
	$(VENV)/bin/ruff check .

bench: setup
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

# System packages (none required for the core today; kept as the one place to add them).
system-deps:
	@true

$(VENV)/.installed: pyproject.toml requirements.lock
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	# torch first and alone: the pinned CPU wheel unless TORCH_SPEC says otherwise,
	# so nothing later can pull an unpinned multi-GB CUDA build.
	$(PIP) install -q $(TORCH_SPEC)
	$(PIP) install -q -r requirements.lock
	$(PIP) install -q --no-deps -e .
	touch $@

# Anny's first build writes ~800 MB of precomputed data; do it once here.
$(ANNY_CACHE_DIR)/.filled: $(VENV)/.installed
	mkdir -p $(ANNY_CACHE_DIR)
	$(PY) -m relightnet.body.cache
	touch $@

clean-venv:
	rm -rf $(VENV)
