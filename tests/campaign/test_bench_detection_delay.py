"""Golden behaviour of the Table I script's detection delay: each drop is matched to the first detection after
it, a drop during a recovery included (the recovery watch's "recovery disturbed"), not to a later firing."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import pytest

_PATH = Path(__file__).resolve().parents[2] / "bench" / "bench_agentchord_table.py"


@pytest.fixture(scope="module")
def delays():  # noqa: ANN201
    spec = importlib.util.spec_from_file_location("bench_agentchord_table", _PATH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.detection_delays


def _record(*events: tuple[float, str]) -> SimpleNamespace:
    return SimpleNamespace(events=[SimpleNamespace(t=t, kind=k) for t, k in events])


def test_a_drop_during_a_recovery_is_detected_by_the_recovery_watch(delays) -> None:  # noqa: ANN001
    r = _record((3.0, "disturbance"), (3.03, "monitor"), (8.44, "disturbance"), (8.47, "recovery disturbed"),
                (15.54, "disturbance"), (15.57, "monitor"))
    assert delays(r) == pytest.approx([3.0, 3.0, 3.0])


def test_a_drop_never_detected_has_no_delay(delays) -> None:  # noqa: ANN001
    assert delays(_record((1.0, "monitor"), (2.0, "disturbance"))) == []
