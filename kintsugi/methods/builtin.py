"""Import every built-in method so its registration runs."""

import importlib
import importlib.util

for _name in ("baseline", "recovery", "scripted", "contact", "agentchord", "coral"):
    if importlib.util.find_spec(f"kintsugi.methods.{_name}") is not None:
        importlib.import_module(f"kintsugi.methods.{_name}")
