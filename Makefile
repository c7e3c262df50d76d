# Two commands for a fresh machine (Python 3.11 + the package registries):
#   make demo   set up, then tour the three systems offline (A peg insertion, B AgentChord against rekep
#               under drops, C CoRAL against L2R), print each system's tables and write runs/demo/index.html
#   make test   set up, build llama.cpp's llama-server once per machine (mk/servers.mk), then run the test suite
#   make test-servers   also build llama-cpp-python's server and run the real-server suite against both
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
		--conditions all --trials 5 --workers 2 --videos-per-cell 1 --out runs/demo/a-peg-insertion
	$(BIN)/kintsugi bench pour-single --methods rekep,agentchord --conditions drop \
		--set disturbance.drop_p=0.3 --trials 3 --workers 2 --videos-per-cell 1 --out runs/demo/b-pour-single
	$(BIN)/kintsugi bench flip-box --methods coral,l2r --trials 1 --workers 2 --videos-per-cell 1 \
		--out runs/demo/c-flip-box
	$(BIN)/kintsugi report runs/demo
	@echo "open runs/demo/index.html: the three systems' tables, a video of each, a page per trial"

include mk/servers.mk
include mk/lerobot.mk

test: setup servers
	KINTSUGI_REAL_SERVERS=1 $(BIN)/pytest -n 2

.PHONY: setup demo test
