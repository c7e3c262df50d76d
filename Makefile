# Two commands for a fresh machine (Python 3.11 + the package registries):
#   make demo   set up, then run a small offline peg-insertion campaign and print its tables
#   make test   set up, then run the test suite
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
export MUJOCO_GL ?= egl

$(BIN)/kintsugi: pyproject.toml constraints.txt
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -c constraints.txt -e '.[test]'
	touch $@

setup: $(BIN)/kintsugi

demo: setup
	$(BIN)/kintsugi bench peg-insertion --methods baseline,recovery --shapes round,square,rectangle \
		--conditions none,all --trials 5 --workers 2 --out runs/demo

test: setup
	$(BIN)/pytest -n 2

.PHONY: setup demo test
