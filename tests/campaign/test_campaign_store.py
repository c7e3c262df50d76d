"""results.jsonl durability (torn last line) and the campaign.json manifest."""

import json

import pytest

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.store import ResultStore
from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import TrialRecord


def rec(seed, **kw):
    return TrialRecord(key=f"t/m/v/c/{seed}", task="t", method="m", variant="v", condition="c", seed=seed,
                       transitions=[("align", "fit")], **kw)


def cfg(**kw):
    return CampaignConfig(**{**dict(task="t", methods=["m"], variants=["v"], conditions=["c"], trials=3), **kw})


def test_append_and_read_roundtrip(tmp_path):
    store = ResultStore(tmp_path)
    with store.appender() as a:
        a.append(rec(0, success=True))
        a.append(rec(1))
    got = store.read()
    assert [r.seed for r in got] == [0, 1]
    assert got[0].success and got[0].transitions == [("align", "fit")]
    assert store.done_keys() == {"t/m/v/c/0", "t/m/v/c/1"}


def test_torn_last_line_is_ignored_then_truncated(tmp_path):
    store = ResultStore(tmp_path)
    good = rec(0).model_dump_json() + "\n"
    torn = rec(1).model_dump_json()[:40]
    store.results_path.write_text(good + torn)
    assert store.done_keys() == {"t/m/v/c/0"}
    assert store.results_path.read_text() == good + torn  # reading never modifies
    with store.appender() as a:
        assert store.results_path.read_text() == good
        a.append(rec(2))
    lines = store.results_path.read_text().splitlines()
    assert len(lines) == 2 and all(json.loads(line) for line in lines)


def test_complete_last_line_without_newline_is_kept(tmp_path):
    store = ResultStore(tmp_path)
    store.results_path.write_text(rec(0).model_dump_json() + "\n" + rec(1).model_dump_json())
    with store.appender() as a:
        a.append(rec(2))
    assert [r.seed for r in store.read()] == [0, 1, 2]


def test_corrupt_middle_line_is_an_error(tmp_path):
    store = ResultStore(tmp_path)
    store.results_path.write_text("{not json\n" + rec(0).model_dump_json() + "\n")
    with pytest.raises(KintsugiError, match="line 1"):
        store.read()


def test_manifest_mismatch_is_a_clear_error(tmp_path):
    store = ResultStore(tmp_path)
    store.ensure_manifest(cfg())
    store.ensure_manifest(cfg())  # same config: fine
    store.ensure_manifest(cfg(trials=10))  # more trials: fine, manifest updated
    assert store.load_config().trials == 10
    with pytest.raises(KintsugiError, match="different config.*methods"):
        store.ensure_manifest(cfg(methods=["m", "other"]))
    with pytest.raises(KintsugiError, match="base_seed"):
        store.ensure_manifest(cfg(base_seed=5))


def test_results_without_manifest_refused(tmp_path):
    store = ResultStore(tmp_path)
    store.results_path.write_text(rec(0).model_dump_json() + "\n")
    with pytest.raises(KintsugiError, match="campaign.json"):
        store.ensure_manifest(cfg())
