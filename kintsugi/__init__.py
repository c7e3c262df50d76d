"""kintsugi: resilient robot manipulation on real MuJoCo physics."""

import os

# Headless offscreen rendering; must be set before mujoco is first imported.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
