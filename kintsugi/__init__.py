"""kintsugi: resilient robot manipulation on real MuJoCo physics."""

__version__ = "0.1.0"
