"""run_campaign end to end on the fake coin task: resume, crashes, errors, executor parity."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from kintsugi.campaign.executors import EXECUTORS, InlineExecutor
from kintsugi.campaign.plan import CampaignConfig, expand
from kintsugi.campaign.runner import run_campaign
from kintsugi.campaign.store import ResultStore
from kintsugi.core.errors import KintsugiError, UnknownNameError

ROOT = Path(__file__).resolve().parents[2]


def cfg(**kw):
    base = dict(task="fake-coin", methods=["plain", "recover"], variants=["fair", "raises"],
                conditions=["easy", "hard"], trials=3, plugins=["tests.fake_tasks"])
    return CampaignConfig(**{**base, **kw})


def file_keys(out):
    return [json.loads(line)["key"] for line in (out / "results.jsonl").read_text().splitlines()]


def test_inline_runs_every_trial_and_records_exceptions(tmp_path):
    c = cfg()
    records = run_campaign(c, tmp_path, executor="inline", progress=False)
    assert [r.key for r in records] == [s.key for s in expand(c)]
    errored = {r.key for r in records if r.error}
    assert errored == {s.key for s in expand(c) if s.variant == "raises" and s.seed % 2 == 0}
    assert all("RuntimeError: fake failure" in r.error for r in records if r.error)
    assert all(not r.success for r in records if r.error)
    assert sorted(file_keys(tmp_path)) == sorted(r.key for r in records)
    assert (tmp_path / "campaign.json").exists()


def test_resume_after_kill_with_torn_line(tmp_path):
    c = cfg()
    reference = {r.key: r for r in run_campaign(c, tmp_path / "ref", executor="inline", progress=False)}
    specs = expand(c)
    out = tmp_path / "run"
    store = ResultStore(out)
    store.ensure_manifest(c)
    # A campaign killed after 5 trials, in the middle of writing the 6th line.
    kept = [reference[s.key].model_copy(update={"params": {"marker": i}}) for i, s in enumerate(specs[:5])]
    torn = reference[specs[5].key].model_dump_json()[:57]
    store.results_path.write_text("".join(r.model_dump_json() + "\n" for r in kept) + torn)

    records = run_campaign(c, out, executor="inline", progress=False)

    keys = file_keys(out)
    assert len(keys) == len(set(keys)) == len(specs)
    assert set(keys) == {s.key for s in specs}
    by_key = {r.key: r for r in records}
    for i, s in enumerate(specs[:5]):  # not rerun: the markers survive
        assert by_key[s.key].params == {"marker": i}
    for s in specs[5:]:
        assert by_key[s.key].without_timings() == reference[s.key].without_timings()
    # A second restart has nothing to do and changes nothing.
    before = (out / "results.jsonl").read_bytes()
    assert len(run_campaign(c, out, executor="inline", progress=False)) == len(specs)
    assert (out / "results.jsonl").read_bytes() == before


def _campaign_process(tmp_path, c, options: str) -> subprocess.Popen:
    """`run_campaign(c, tmp_path / "out", <options>)` in a child Python process (to be killed by the test)."""
    (tmp_path / "cfg.json").write_text(c.model_dump_json())
    script = (
        "import sys; from pathlib import Path; "
        "from kintsugi.campaign.plan import CampaignConfig; from kintsugi.campaign.runner import run_campaign; "
        "run_campaign(CampaignConfig.model_validate_json(Path(sys.argv[1]).read_text()), sys.argv[2], "
        f"{options}, progress=False)"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-c", script, str(tmp_path / "cfg.json"), str(tmp_path / "out")],
                            cwd=ROOT, env=env)


@pytest.mark.slow
def test_real_sigkill_then_resume(tmp_path):
    """Kill a running campaign process at an arbitrary moment; the rerun completes it exactly once."""
    c = cfg(variants=["slow"], conditions=["easy"], trials=20)
    proc = _campaign_process(tmp_path, c, "executor='inline'")
    results = tmp_path / "out" / "results.jsonl"
    deadline = time.monotonic() + 90  # a loaded machine may take long to start the process
    while time.monotonic() < deadline and proc.poll() is None:
        if results.exists() and results.read_bytes().count(b"\n") >= 5:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_before = results.read_bytes().count(b"\n")
    assert 5 <= n_before < 40, "the campaign should have been killed part way"

    records = run_campaign(c, tmp_path / "out", executor="inline", progress=False)
    keys = file_keys(tmp_path / "out")
    assert len(keys) == len(set(keys)) == 40
    assert {r.key for r in records} == {s.key for s in expand(c)}


def test_growing_trials_runs_only_new_seeds(tmp_path):
    small = run_campaign(cfg(trials=2), tmp_path, executor="inline", progress=False)
    marked = tmp_path / "results.jsonl"
    # Mark the old lines so a rerun of them would be visible.
    lines = [json.loads(line) for line in marked.read_text().splitlines()]
    marked.write_text("".join(json.dumps({**d, "params": {"old": True}}) + "\n" for d in lines))
    grown = run_campaign(cfg(trials=4), tmp_path, executor="inline", progress=False)
    assert len(small) == 16 and len(grown) == 32
    assert sum(r.params == {"old": True} for r in grown) == 16
    assert ResultStore(tmp_path).load_config().trials == 4


def test_config_mismatch_refused_before_running(tmp_path):
    run_campaign(cfg(trials=1), tmp_path, executor="inline", progress=False)
    with pytest.raises(KintsugiError, match="different config"):
        run_campaign(cfg(trials=1, base_seed=100), tmp_path, executor="inline", progress=False)


@pytest.mark.slow
def test_process_and_inline_give_the_same_records(tmp_path):
    c = cfg()
    proc = run_campaign(c, tmp_path / "proc", workers=2, executor="process", progress=False)
    inline = run_campaign(c, tmp_path / "inline", executor="inline", progress=False)
    assert [r.key for r in proc] == [s.key for s in expand(c)]
    assert [r.without_timings() for r in proc] == [r.without_timings() for r in inline]
    # Exceptions in trials carry their message across the process boundary.
    assert any(r.error and "fake failure" in r.error for r in proc)


@pytest.mark.slow
def test_crashed_worker_is_a_failed_trial_and_the_campaign_goes_on(tmp_path):
    """Seed 1 kills its worker while seed 0 is certainly running in the same pool (a file barrier):
    both are rerun alone, only seed 1 is recorded as crashed, and the later trials still run."""
    barrier = tmp_path / "barrier"
    barrier.mkdir()
    c = cfg(methods=["plain"], variants=["crashes", "fair"], conditions=["easy"], trials=3,
            overrides={"barrier_dir": str(barrier)})
    out = tmp_path / "out"
    records = run_campaign(c, out, workers=2, executor="process", progress=False)
    assert [r.key for r in records] == [s.key for s in expand(c)]
    crashed = [r for r in records if r.error]
    assert [r.key for r in crashed] == ["fake-coin/plain/crashes/easy/1"]
    assert "worker process crashed" in crashed[0].error and "rerun alone" in crashed[0].error
    assert not crashed[0].success
    # The innocent trials that shared the broken pool got their real result.
    inline_cfg = c.model_copy(update={"variants": ["fair"]})
    inline = run_campaign(inline_cfg, tmp_path / "inline", executor="inline", progress=False)
    seed0 = next(r for r in records if r.key == "fake-coin/plain/crashes/easy/0")
    assert seed0.without_timings()["success"] in (True, False) and seed0.params == {"p": 0.6}
    assert [r.without_timings() for r in records if r.variant == "fair"] == [r.without_timings() for r in inline]
    keys = file_keys(out)
    assert len(keys) == len(set(keys)) == len(records)
    # The recorded crash is not rerun on resume.
    before = (out / "results.jsonl").read_bytes()
    assert len(run_campaign(c, out, executor="process", progress=False)) == len(records)
    assert (out / "results.jsonl").read_bytes() == before


@pytest.mark.slow
def test_hung_trial_is_killed_at_the_timeout_and_the_others_still_run(tmp_path):
    """Seed 1 sleeps 60 s; with a 2 s timeout it is recorded as timed out, the trial that shared its pool
    is started again and gets its real result, and the campaign ends in seconds, not a minute."""
    c = cfg(methods=["plain"], variants=["hangs"], conditions=["easy"], trials=4)
    t0 = time.monotonic()
    records = run_campaign(c, tmp_path / "out", workers=2, executor="process", progress=False, trial_timeout_s=2.0)
    assert time.monotonic() - t0 < 30
    assert [r.key for r in records] == [s.key for s in expand(c)]
    hung = [r for r in records if r.error]
    assert [r.seed for r in hung] == [1] and "timed out" in hung[0].error and "2 s" in hung[0].error
    inline = run_campaign(c.model_copy(update={"trials": 1}), tmp_path / "inline", executor="inline", progress=False)
    assert records[0].without_timings() == inline[0].without_timings()
    assert all(r.error is None for r in records if r.seed != 1)


@EXECUTORS.register("wrong-identity", "a buggy executor: yields each trial with another trial's record")
class WrongIdentityExecutor(InlineExecutor):
    def run(self, specs):
        for spec, record in super().run(specs):
            yield spec, record.model_copy(update={"key": "bogus", "seed": record.seed + 100})


def test_record_with_wrong_identity_becomes_failure(tmp_path):
    records = run_campaign(cfg(variants=["fair"], conditions=["easy"], methods=["plain"], trials=2),
                           tmp_path, executor="wrong-identity", progress=False)
    assert [r.key for r in records] == ["fake-coin/plain/fair/easy/0", "fake-coin/plain/fair/easy/1"]
    assert all("key, seed do not match the trial" in r.error and not r.success for r in records)


def test_clear_errors_for_bad_setup(tmp_path):
    with pytest.raises(UnknownNameError, match="inline.*process"):
        run_campaign(cfg(), tmp_path, executor="nope", progress=False)
    with pytest.raises(KintsugiError, match="unknown task 'no-such-task'"):
        run_campaign(cfg(task="no-such-task"), tmp_path, executor="inline", progress=False)
    with pytest.raises(KintsugiError, match="plugin module 'no_such_plugin_mod'"):
        run_campaign(cfg(plugins=["no_such_plugin_mod"]), tmp_path, executor="inline", progress=False)
    try:
        import ray  # noqa: F401
    except ImportError:
        with pytest.raises(KintsugiError, match=r"pip install 'kintsugi\[ray\]'"):
            run_campaign(cfg(), tmp_path, executor="ray", progress=False)
    assert not (tmp_path / "results.jsonl").exists()


def test_progress_bar_renders(tmp_path):
    from io import StringIO

    from rich.console import Console

    buf = StringIO()
    run_campaign(cfg(trials=1), tmp_path, executor="inline", console=Console(file=buf, width=120))
    run_campaign(cfg(trials=2), tmp_path, executor="inline", console=Console(file=buf, width=120))
    text = buf.getvalue()
    assert "16/16" in text and "resuming" in text and "errors" in text


def _children(pid: int) -> set[int]:
    """Live processes whose parent is pid (from /proc)."""
    out = set()
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                fields = (d / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                out.add(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _running_process_campaign(tmp_path) -> tuple[subprocess.Popen, set[int]]:
    """A process-executor campaign of slow fake trials in a child process, started and holding workers."""
    c = cfg(variants=["hangs"], conditions=["easy"], methods=["plain"], trials=3)
    proc = _campaign_process(tmp_path, c, "workers=2, executor='process'")
    results = tmp_path / "out" / "results.jsonl"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (results.exists() and results.read_bytes().count(b"\n") >= 1):
        time.sleep(0.05)  # seed 0 done in 0.3 s; seed 1 sleeps 60 s in its worker
    workers = {p for p in _children(proc.pid) if "spawn_main" in (Path("/proc") / str(p) / "cmdline").read_text()}
    assert proc.poll() is None and workers, "the campaign should be running with its workers"
    return proc, workers


def _gone(pids: set[int], within_s: float) -> bool:
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline:
        if not any(_alive(p) for p in pids):
            return True
        time.sleep(0.05)
    return False


@pytest.mark.slow
def test_sigterm_stops_the_campaign_and_its_workers(tmp_path):
    proc, workers = _running_process_campaign(tmp_path)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=20) == 128 + signal.SIGTERM  # unwound (SystemExit), not struck dead (-15)
    assert _gone(workers, 5.0), "a terminated campaign must not leave its workers running"


@pytest.mark.slow
def test_workers_of_a_killed_campaign_exit_on_their_own(tmp_path):
    """SIGKILL runs no handler in the campaign process: each worker notices it is orphaned and exits."""
    from kintsugi.campaign.executors import ORPHAN_POLL_S

    proc, workers = _running_process_campaign(tmp_path)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert _gone(workers, 10 * ORPHAN_POLL_S + 2.0), "orphaned workers must exit"
