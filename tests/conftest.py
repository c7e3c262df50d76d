"""Suite-wide settings and fixtures.

Property tests draw the same examples on every run (deterministic CI), and a loaded 2-core machine
never fails a property test on timing alone. `fake_openai` (a running local chat-completions server
with scripted replies, `tests/fake_openai_server.py`) is available to every test without an import.
Tests marked `slow` (whole trials, process pools, fuzzing) are skipped by `pytest -m "not slow"`.
"""

from hypothesis import settings

from tests.fake_openai_server import fake_openai  # noqa: F401 - a fixture for every test module

settings.register_profile("kintsugi", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("kintsugi")
