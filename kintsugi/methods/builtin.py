"""Import every built-in method so its registration runs."""

import importlib

for _module in ("recovery.baseline", "recovery.method", "scripted", "expert.method", "agentchord.method",
                "agentchord.replanning", "coral", "policy"):
    importlib.import_module(f"kintsugi.methods.{_module}")
