# Two commands for a fresh machine (Python 3.11 + the package registries):
#   make demo   set up, then run a small offline campaign of each system (A peg insertion, B AgentChord,
#               C CoRAL) and print their tables
#   make test   set up, build the real model servers once per machine (mk/servers.mk), then run the test suite
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
		--conditions none,all --trials 5 --workers 2 --out runs/demo/peg-insertion
	$(BIN)/kintsugi bench pour-single --methods scripted,agentchord --conditions drop \
		--set disturbance.drop_p=0.3 --trials 3 --workers 2 --out runs/demo/pour-single
	$(BIN)/kintsugi bench flip-box --methods coral,l2r --trials 2 --workers 2 --out runs/demo/flip-box

include mk/servers.mk

test: setup servers
	$(BIN)/pytest -n 2

.PHONY: setup demo test
