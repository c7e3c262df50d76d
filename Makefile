# Two commands for a fresh machine (Python 3.11 + the package registries):
#   make demo   set up, then tour the three systems offline (A peg insertion, B AgentChord against rekep
#               under drops, C CoRAL against L2R), print each system's tables and write runs/demo/index.html
#   make test   set up, build llama.cpp's llama-server and llama-cpp-python's server once per machine
#               (mk/servers.mk), then run the test suite, the real-server suite included
#   make test-servers   build both real servers and run only the real-server suite
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
export MUJOCO_GL ?= egl
# Every process of a campaign or of the test suite imports about 1,800 modules: with PYTHONDONTWRITEBYTECODE set
# (some environments set it) none of their bytecode is kept, and each process spends ~2 s of CPU compiling them
# again. The project's own venv and source tree keep theirs.
unexport PYTHONDONTWRITEBYTECODE

# The demo needs only kintsugi's own dependencies; the tests add pytest, ray, h5py, pyarrow and gymnasium.
# --no-compile: Python compiles only the modules a run imports, on first import (a third of the install's CPU).
$(BIN)/kintsugi: pyproject.toml constraints.txt
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --no-compile -c constraints.txt -e .
	touch $@

$(VENV)/.test-installed: $(BIN)/kintsugi
	$(BIN)/pip install --quiet -c constraints.txt -e '.[test]'
	touch $@

setup: $(VENV)/.test-installed

DEMO := runs/demo
demo-a: $(BIN)/kintsugi
	-$(BIN)/kintsugi bench peg-insertion --methods baseline,recovery --shapes round,square,rectangle \
		--conditions all --trials 5 --executor inline --videos-per-cell 1 --out $(DEMO)/a-peg-insertion
demo-b: $(BIN)/kintsugi
	-$(BIN)/kintsugi bench pour-single --methods rekep,agentchord --conditions drop \
		--set disturbance.drop_p=0.3 --trials 3 --executor inline --videos-per-cell 1 --out $(DEMO)/b-pour-single
demo-c: $(BIN)/kintsugi
	-$(BIN)/kintsugi bench flip-box --methods coral,l2r --trials 1 --executor inline --videos-per-cell 1 \
		--out $(DEMO)/c-flip-box

# The three campaigns run side by side, each in one process (no worker pool to start); each prints its tables
# and writes its report when it ends, then one index links the three. A trial that errors is reported by its
# campaign (and counts as a failure) without stopping the tour.
demo: $(BIN)/kintsugi
	@echo "running A, B and C side by side: each prints its tables when it ends"
	@$(MAKE) --no-print-directory -j3 --output-sync=target demo-a demo-b demo-c
	$(BIN)/kintsugi report $(DEMO) --index-only
	@echo "open $(DEMO)/index.html: the three systems' tables, a video of each, a page per trial"

include mk/servers.mk
include mk/lerobot.mk

test: setup servers
	KINTSUGI_REAL_SERVERS=1 $(BIN)/pytest -n 2

.PHONY: setup demo demo-a demo-b demo-c test
