"""Where registry entries come from: `load_plugins` modules and installed packages' `kintsugi.plugins`
entry points (a replaced entry-point lookup, and a tiny dist-info on the path); every failure is one line
naming the module or entry point."""

from __future__ import annotations

import importlib
import sys
from importlib.metadata import EntryPoint
from pathlib import Path
from typing import Iterator

import pytest

from kintsugi.core import plugins
from kintsugi.core.errors import ConfigError
from kintsugi.core.registry import METHODS, TASKS

PLUGIN = '''
import dataclasses

from kintsugi.worlds.tabletop.task import register
from tests.plugins.toy_tabletop import SPEC

register(dataclasses.replace(SPEC, name="toy-from-entry-point"))
'''


@pytest.fixture
def isolated(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[Path]:
    """Registrations, loaded-module bookkeeping and the test's modules (`kintsugi_*.py` written to
    `tmp_path`, which is importable) are undone after the test."""
    plugins.load_plugins(["tests.plugins.toy_tabletop"])  # registered for good, before the copies
    monkeypatch.setattr(TASKS, "_entries", dict(TASKS._entries))
    monkeypatch.setattr(METHODS, "_entries", dict(METHODS._entries))
    monkeypatch.setattr(plugins, "_loaded", set(plugins._loaded))
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    for name in [m for m in sys.modules if m.startswith("kintsugi_")]:
        del sys.modules[name]


def _write(where: Path, module: str, source: str) -> None:
    (where / f"{module}.py").write_text(source)
    importlib.invalidate_caches()


def _installed(monkeypatch: pytest.MonkeyPatch, *eps: EntryPoint) -> None:
    """Pretend an installed distribution declares these entry points."""
    def entry_points(group: str | None = None) -> list[EntryPoint]:
        return [ep for ep in eps if ep.group == group]

    monkeypatch.setattr(plugins, "entry_points", entry_points)


def _ep(name: str, value: str) -> EntryPoint:
    return EntryPoint(name=name, value=value, group=plugins.ENTRY_POINT_GROUP)


def test_an_entry_point_registers_its_task(isolated: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _write(isolated, "kintsugi_ep_tasks", PLUGIN)
    _installed(monkeypatch, _ep("toy", "kintsugi_ep_tasks"))
    assert "toy-from-entry-point" not in TASKS
    plugins.load_builtins()
    task = TASKS.get("toy-from-entry-point").factory()
    assert task.reference_method == "scripted" and "pour-single" in TASKS  # beside the built-ins
    plugins.load_builtins()  # loaded once: no "registered twice"


@pytest.mark.parametrize(("value", "needles"), [
    ("kintsugi_ep_missing", ["entry point 'broken'", "(kintsugi_ep_missing)", "failed to load",
                             "ModuleNotFoundError"]),
    ("kintsugi_ep_raises", ["entry point 'broken'", "RuntimeError: needs a robot arm driver"]),
    ("kintsugi_ep_tasks:no_such_attr", ["entry point 'broken'", "AttributeError"]),
])
def test_a_broken_entry_point_is_one_clear_error(isolated: Path, monkeypatch: pytest.MonkeyPatch, value: str,
                                                 needles: list[str]) -> None:
    _write(isolated, "kintsugi_ep_raises", 'raise RuntimeError("needs a robot arm driver\\nmore")\n')
    _write(isolated, "kintsugi_ep_tasks", PLUGIN)
    _installed(monkeypatch, _ep("broken", value))
    with pytest.raises(ConfigError) as info:
        plugins.load_builtins()
    message = str(info.value)
    assert "\n" not in message
    for needle in needles:
        assert needle in message, message


def test_load_plugins_imports_modules_after_the_builtins(isolated: Path) -> None:
    _write(isolated, "kintsugi_user_tasks", PLUGIN)
    plugins.load_plugins(["kintsugi_user_tasks"])
    assert "toy-from-entry-point" in TASKS and "peg-insertion" in TASKS and "scripted" in METHODS
    plugins.load_plugins(["kintsugi_user_tasks"])  # idempotent


@pytest.mark.parametrize(("module", "source", "needles"), [
    ("kintsugi_nowhere", None, ["plugin module 'kintsugi_nowhere' not found", "PYTHONPATH"]),
    ("kintsugi_nowhere.tasks", None, ["plugin module 'kintsugi_nowhere.tasks' not found"]),
    ("kintsugi_bad_dep", "import kintsugi_no_such_dependency\n",
     ["plugin module 'kintsugi_bad_dep' failed to import", "No module named 'kintsugi_no_such_dependency'"]),
    ("kintsugi_bad_syntax", "def broken(:\n", ["plugin module 'kintsugi_bad_syntax' failed to import",
                                               "SyntaxError"]),
    ("kintsugi_twice", "from kintsugi.core.registry import TASKS\n"
                       "TASKS.register('pick-box', 'again')(lambda: None)\n",
     ["plugin module 'kintsugi_twice' failed to import", "task 'pick-box' registered twice"]),
])
def test_a_module_that_does_not_import_is_one_clear_error(isolated: Path, module: str, source: str | None,
                                                           needles: list[str]) -> None:
    if source is not None:
        _write(isolated, module, source)
    with pytest.raises(ConfigError) as info:
        plugins.load_plugins([module])
    message = str(info.value)
    assert "\n" not in message
    for needle in needles:
        assert needle in message, message


def test_an_installed_distribution_is_found_on_the_path(isolated: Path) -> None:
    """A real (if tiny) installed distribution: its dist-info names the entry points importlib finds."""
    dist = isolated / "kintsugi_fake_tasks-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: kintsugi-fake-tasks\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[kintsugi.plugins]\ntoy = kintsugi_dist_tasks\n")
    _write(isolated, "kintsugi_dist_tasks", PLUGIN)
    plugins.load_builtins()
    assert "toy-from-entry-point" in TASKS
    (dist / "entry_points.txt").write_text("[kintsugi.plugins]\nbroken = kintsugi_dist_missing\n")
    with pytest.raises(ConfigError, match="entry point 'broken' of package 'kintsugi-fake-tasks' "
                                          r"\(kintsugi_dist_missing\) failed to load: ModuleNotFoundError"):
        plugins.load_builtins()
