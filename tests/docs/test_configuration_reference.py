"""docs/configuration.md is generated from the typed configs and must match them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_configuration_reference_is_current() -> None:
    # A fresh interpreter: this process's registries also hold what other tests registered (plugins, toys).
    done = subprocess.run([sys.executable, str(ROOT / "docs" / "tools" / "configuration.py"), "--check"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr


def test_the_reference_names_every_settable_key_of_a_task_and_a_method() -> None:
    from kintsugi.core.resolve import flatten_settings, settings_document

    text = (ROOT / "docs" / "configuration.md").read_text()
    keys = flatten_settings(settings_document("peg-insertion", "recovery", {}))
    for key in keys:
        shown = key.replace("methods.recovery.", "method.")
        assert f"| `{shown}` |" in text, shown
