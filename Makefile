# rczone developer tasks. Every target creates .venv on first use, with the pinned versions of
# constraints.txt (pyproject.toml keeps the floors for users; `make lock` re-pins on purpose).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
PIP := $(BIN)/python -m pip install --quiet -c constraints.txt

.PHONY: test demo lint format bench docs lock clean

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PIP) --upgrade pip setuptools
	$(PIP) --no-build-isolation -e ".[dev]"
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow" -n auto --dist loadfile

demo: $(STAMP)
	$(BIN)/rczone demo --out demo-output

lint: $(STAMP)
	$(BIN)/ruff check src tests bench validation
	$(BIN)/ruff format --check src tests bench validation

format: $(STAMP)
	$(BIN)/ruff format src tests bench validation
	$(BIN)/ruff check --fix src tests bench validation

bench: $(STAMP)
	$(BIN)/python bench/first_run.py
	$(BIN)/python bench/run.py
	$(BIN)/python bench/limit.py
	$(BIN)/python bench/batch.py

# The guides and the API reference (Sphinx + MyST + numpydoc) into docs/_build/html; warnings are errors.
docs: $(STAMP)
	$(BIN)/python -m sphinx -b html -q -E -W --keep-going docs docs/_build/html

# Re-resolve every dependency and pin it in constraints.txt (see its header).
lock:
	bash .ci/lock

clean:
	rm -rf $(VENV) demo-output .pytest_cache docs/_build
