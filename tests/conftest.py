"""Suite-wide settings and fixtures.

Property tests draw the same examples on every run (deterministic CI), and a loaded 2-core machine
never fails a property test on timing alone. `fake_openai` (a running local chat-completions server
with scripted replies, `tests/fake_openai_server.py`) is available to every test without an import.
Tests marked `slow` (whole trials, process pools, fuzzing) are skipped by `pytest -m "not slow"`.
Entries a test registers from its own modules (toy tasks, methods, backends, executors) are removed
after it, so no test sees another's toys; kintsugi's own entries, registered lazily on first use,
stay.
"""

import sys

import pytest
from hypothesis import settings

from kintsugi.campaign.executors import EXECUTORS
from kintsugi.core import plugins
from kintsugi.core.registry import METHODS, REASONERS, TASKS

from tests.fake_openai_server import fake_openai  # noqa: F401 - a fixture for every test module

settings.register_profile("kintsugi", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("kintsugi")


def _is_test_owned(factory: object) -> bool:
    return not getattr(factory, "__module__", "kintsugi.").startswith("kintsugi.")


@pytest.fixture(autouse=True)
def _forget_test_registrations():
    """Drop what the test registered from outside the package, whichever registry it used; a module the
    test imported to register them (a plugin) is forgotten too, so the next import registers again."""
    registries = (TASKS, METHODS, REASONERS, EXECUTORS)
    before = [set(r._entries) for r in registries]
    modules_before = set(sys.modules)
    yield
    for registry, names in zip(registries, before):
        for name in set(registry._entries) - names:
            factory = registry._entries[name].factory
            if not _is_test_owned(factory):
                continue
            del registry._entries[name]
            module = factory.__module__
            if module not in modules_before:
                sys.modules.pop(module, None)
                plugins._loaded.difference_update({v for v in plugins._loaded if v.split(":")[0] == module})
