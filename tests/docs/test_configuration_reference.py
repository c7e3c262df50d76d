"""docs/configuration.md is generated from the typed configs and must match them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _tool():  # noqa: ANN202 - the generator module, loaded from its file
    spec = importlib.util.spec_from_file_location("configuration_tool", ROOT / "docs" / "tools" / "configuration.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_configuration_reference_is_current() -> None:
    tool = _tool()
    text = tool.render()
    assert tool.OUT.read_text() == text, "docs/configuration.md is out of date: run " \
                                         ".venv/bin/python docs/tools/configuration.py"


def test_the_reference_names_every_settable_key_of_a_task_and_a_method() -> None:
    from kintsugi.core.resolve import flatten_settings, settings_document

    text = (ROOT / "docs" / "configuration.md").read_text()
    keys = flatten_settings(settings_document("peg-insertion", "recovery", {}))
    for key in keys:
        shown = key.replace("methods.recovery.", "method.")
        assert f"| `{shown}` |" in text, shown
