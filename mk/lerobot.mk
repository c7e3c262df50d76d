# The optional LeRobot environment: loads kintsugi's LeRobot v3.0 exports with LeRobot's own LeRobotDataset.
# LeRobot pins an older torch than this machine's CPU build, so it is installed without its pins, beside the
# torch and torchvision pip finds (`LEROBOT_TORCH`), with what its dataset module imports. Videos decode with
# torchcodec (torchvision 0.29 has no VideoReader for LeRobot's pyav path), which needs FFmpeg's shared libraries
# (Debian's ffmpeg package; installed here when apt-get is there and they are missing).
# Included from the Makefile: `make lerobot-check` installs .venv-lerobot once, then runs the load tests.
LEROBOT_VENV ?= .venv-lerobot
LEROBOT_VERSION ?= 0.4.4
LEROBOT_TORCH ?= torch==2.14.1 torchvision==0.29.1
LEROBOT_DEPS ?= datasets huggingface_hub pandas pyarrow av jsonlines packaging draccus einops imageio \
	imageio-ffmpeg numpy deepdiff termcolor accelerate torchcodec

$(LEROBOT_VENV)/.installed:
	@ldconfig -p | grep -q libavcodec || { command -v apt-get >/dev/null && apt-get install -y -qq ffmpeg; } \
		|| echo "FFmpeg's shared libraries are missing: LeRobot cannot decode the exported videos"
	python3 -m venv $(LEROBOT_VENV)
	$(LEROBOT_VENV)/bin/pip install -q $(LEROBOT_TORCH)
	$(LEROBOT_VENV)/bin/pip install -q --no-deps lerobot==$(LEROBOT_VERSION)
	$(LEROBOT_VENV)/bin/pip install -q $(LEROBOT_DEPS)
	$(LEROBOT_VENV)/bin/python -c "import lerobot.datasets.lerobot_dataset"
	touch $@

.PHONY: lerobot-env lerobot-check
lerobot-env: $(LEROBOT_VENV)/.installed

lerobot-check: lerobot-env
	MUJOCO_GL=egl KINTSUGI_LEROBOT_PYTHON=$(LEROBOT_VENV)/bin/python .venv/bin/pytest tests/export/test_lerobot_load.py -q
