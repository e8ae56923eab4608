# Two commands on a fresh machine:  make demo   and   make test
# Each creates .venv and installs the project (PyPI only) on first use.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: demo test bench report docs lint clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rasterhw demo --out out

test: $(STAMP)
	$(PY) -m pytest -q -n 2

bench: $(STAMP)
	$(VENV)/bin/rasterhw bench

docs: $(STAMP)
	$(VENV)/bin/rasterhw report all

lint: $(STAMP)
	$(VENV)/bin/ruff check .

clean:
	rm -rf build out .pytest_cache
