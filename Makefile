# Two commands on a fresh machine:  make demo   and   make test
# Each creates .venv and installs the project (PyPI only) on first use.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: demo test slow bench soak report docs lint clean

$(STAMP): pyproject.toml setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rasterhw demo --out out

test: $(STAMP)
	$(PY) -m pytest -q -n 2 -m "not slow" --durations=15

# long sweeps (marked slow): a benchmark-sized run, not part of CI
slow: $(STAMP)
	$(PY) -m pytest -q -n 2 -m slow --durations=15

bench: $(STAMP)
	$(VENV)/bin/rasterhw bench

# random differential runs, 10^8 output pixels per HDL block (hours; SEED=n reruns one)
soak: $(STAMP)
	$(VENV)/bin/rasterhw soak --pixels 100000000 $(if $(SEED),--seed $(SEED))

docs: $(STAMP)
	$(VENV)/bin/rasterhw report all

lint: $(STAMP)
	$(VENV)/bin/ruff check .

clean:
	rm -rf build out .pytest_cache
