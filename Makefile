# One-command set-up: every target creates $(VENV) when it is missing and installs the package.
# PYTHON defaults to the newest supported interpreter that runs (3.13, 3.12, then 3.11; a
# command on PATH first, then pyenv's versions); a command that exists but fails, such as a
# pyenv shim for a version not selected, is skipped. Override: make test PYTHON=... VENV=...
SUPPORTED := 3.13 3.12 3.11
PYTHONS := $(shell for v in $(SUPPORTED); do \
	for c in python$$v $$(ls -d $$HOME/.pyenv/versions/$$v.*/bin/python$$v 2>/dev/null | sort -rV); do \
	$$c -c "import sys, venv" >/dev/null 2>&1 && { echo $$c; break; }; done; done)
PYTHON ?= $(firstword $(PYTHONS))
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEMO_STAMP := $(VENV)/.installed-demo

.PHONY: demo docs test bench pythons clean

$(PY):
	@test -n "$(PYTHON)" || { echo "no Python $(SUPPORTED) found that runs; set PYTHON=..."; exit 1; }
	$(PYTHON) -m venv $(VENV)

# The version is read from drake_auv/__init__.py: a new one reinstalls.
# Everything: the tests (their extra brings the campaign and docs extras) and the reconstruction.
$(STAMP): $(PY) pyproject.toml drake_auv/__init__.py
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,reconstruct]"
	touch $(STAMP)

# Only what the demo uses: the core (run, plan) and the reconstruction of its surface.
$(DEMO_STAMP): $(PY) pyproject.toml drake_auv/__init__.py
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[reconstruct]"
	touch $(DEMO_STAMP)

demo: $(DEMO_STAMP)
	MPLBACKEND=Agg $(VENV)/bin/drake-auv demo --out out/demo

# the demo's figures and numbers, the API reference (out/docs/api) and the tutorial executed
docs: $(STAMP)
	MPLBACKEND=Agg $(PY) scripts/update_docs.py --out out/docs

test: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest -q

bench: $(STAMP)
	@for f in benchmarks/bench_*.py; do echo "== $$f"; MPLBACKEND=Agg $(PY) $$f || exit 1; done

pythons:  # the supported interpreters that run, newest first
	@echo $(PYTHONS)

clean:
	rm -rf .venv .venv-* out build *.egg-info
