"""Where trials run: a registry of executors, each yielding records as trials finish.

- `process` (default): a spawn-started process pool. Spawn, not fork, because
  workers render with EGL and a forked GL context is undefined behaviour. A worker
  that dies (segfault, os._exit) breaks the pool; the trials it held are rerun one
  per fresh single-worker pool, so the one that crashes again is recorded as a
  failed trial and the innocent ones get their real result. The pool is then
  recreated and the campaign goes on. A trial running longer than the trial
  timeout is killed with its pool and recorded as failed; the other trials that
  were running in that pool are started again.
- `inline`: same process, one after another; for debugging (a crash kills you).
- `ray`: one ray task per trial, for users with a cluster.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import signal
import threading
import time
from collections import deque
from contextlib import contextmanager
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Iterable, Iterator, Protocol

from kintsugi.campaign.bootstrap import bootstrap
from kintsugi.core.errors import KintsugiError
from kintsugi.core.registry import Registry
from kintsugi.core.record import TrialRecord, TrialSpec
from kintsugi.core.runner import failed_record, run_trial


class Executor(Protocol):
    def run(self, specs: Iterable[TrialSpec]) -> Iterator[tuple[TrialSpec, TrialRecord]]:
        """Run every spec; yield (spec, record) once per spec, in finishing order."""
        ...


ExecutorFactory = Callable[..., Executor]
"""(workers, plugins, trial_timeout_s=None) -> Executor."""
EXECUTORS: Registry[ExecutorFactory] = Registry("executor")


def run_in_worker(spec: TrialSpec, plugins: list[str]) -> TrialRecord:
    """Worker entry point: make the task known in this process, then run the trial."""
    try:
        bootstrap(plugins, spec.task)
    except KintsugiError as exc:
        return failed_record(spec, f"KintsugiError: {exc}")
    return run_trial(spec)


ORPHAN_POLL_S = 0.5


def _worker_init() -> None:
    """Ctrl-C is the main process's to handle (it stops the pool); a worker must not turn it
    into a recorded 'KeyboardInterrupt' failure of the trial it was running. And a worker whose
    campaign process is gone (killed with SIGKILL, or crashed) exits instead of running on alone:
    nothing would record its trial, and it would hold a core."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(ORPHAN_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="orphan-watch", daemon=True).start()


@contextmanager
def _terminate_as_exit() -> Iterator[None]:
    """SIGTERM (`kill`, a cluster's job stop) unwinds like Ctrl-C, so the pools are killed on the way
    out; Python's default would end the process at once and leave the workers running."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum: int, frame: object) -> None:
        raise SystemExit(128 + signum)

    previous = signal.signal(signal.SIGTERM, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _kill(pool: ProcessPoolExecutor) -> None:
    """Stop a pool now, running trials included (Python 3.14 has kill_workers; older ones do not).
    The workers are read before the shutdown, which forgets them (`_processes = None`)."""
    kill = getattr(pool, "kill_workers", None)
    if kill is not None:
        kill()  # shuts the pool down too
        return
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.kill()


def warm_up(plugins: list[str]) -> int:
    """Start a worker and import the plugins and built-in tasks in it (errors surface later, per trial).

    Every trial calls `load_builtins()`; importing the worlds (MuJoCo, OpenCV, mink) takes seconds on a
    loaded machine, which must not be charged to the first trial's timeout.
    """
    from kintsugi.core.plugins import load_builtins

    for load in [*(lambda m=m: importlib.import_module(m) for m in plugins), load_builtins]:
        try:
            load()
        except Exception:  # noqa: BLE001 - reported by the trial that needs it
            pass
    return os.getpid()


_CRASH = (
    "worker process crashed while running this trial (segfault, os._exit or out of memory{how}): {{exc}}. "
    "Rerun this trial with the inline executor to see the crash."
)
CRASH_ONLY = _CRASH.format(how="; it was the only trial in its worker pool")
CRASH_ALONE = _CRASH.format(how="; it crashed again when rerun alone")
TIMED_OUT = ("trial timed out: still running after {limit:g} s (the campaign's trial timeout, --trial-timeout); "
             "its worker was killed. Rerun it alone with `kintsugi run` to see where it hangs.")


@EXECUTORS.register("inline", "run trials one by one in this process (debugging; a crash ends the campaign)")
class InlineExecutor:
    """No trial timeout: nothing can stop a trial running in this very process."""

    def __init__(self, workers: int, plugins: list[str], trial_timeout_s: float | None = None) -> None:
        self.plugins = list(plugins)

    def run(self, specs: Iterable[TrialSpec]) -> Iterator[tuple[TrialSpec, TrialRecord]]:
        for spec in specs:
            yield spec, run_in_worker(spec, self.plugins)


@EXECUTORS.register("process", "spawn-started process pool on this machine (default)", tags=("default",))
class ProcessExecutor:
    def __init__(self, workers: int, plugins: list[str], trial_timeout_s: float | None = None) -> None:
        if workers < 1:
            raise KintsugiError(f"workers must be >= 1, got {workers}")
        if trial_timeout_s is not None and not trial_timeout_s > 0:
            raise KintsugiError(f"the trial timeout must be > 0 seconds, got {trial_timeout_s}")
        self.timeout = trial_timeout_s
        self.workers = workers
        self.plugins = list(plugins)
        self._ctx = multiprocessing.get_context("spawn")

    def _pool(self, workers: int) -> ProcessPoolExecutor:
        """A pool whose workers are all started before the first trial.

        CPython's pool (3.11-3.13) spawns workers lazily and its manager thread
        can miss the death of one spawned after it began waiting; the crash
        then goes unnoticed until another result arrives (or forever, if none
        does). Starting every worker up front with a warm-up task (which also
        imports the plugins and the built-in tasks, so a trial's timeout counts the
        trial, not the imports) closes that gap.
        """
        pool = ProcessPoolExecutor(max_workers=workers, mp_context=self._ctx, initializer=_worker_init)
        warmups = [pool.submit(warm_up, self.plugins) for _ in range(workers)]
        wait(warmups)
        if any(isinstance(f.exception(), BrokenProcessPool) for f in warmups):
            pool.shutdown(wait=False, cancel_futures=True)
            raise KintsugiError(
                "worker processes die while starting (before any trial ran); "
                "run with the inline executor to see why"
            )
        return pool

    def run(self, specs: Iterable[TrialSpec]) -> Iterator[tuple[TrialSpec, TrialRecord]]:
        with _terminate_as_exit():
            yield from self._run(specs)

    def _run(self, specs: Iterable[TrialSpec]) -> Iterator[tuple[TrialSpec, TrialRecord]]:
        queue = deque(specs)
        if not queue:
            return
        # Never more workers than trials left: a resumed campaign with 1 trial to go
        # (or the tail after a crash) does not start a full pool.
        size = min(self.workers, len(queue))
        pool = self._pool(size)
        # Only `workers` trials are submitted at a time, so when the pool breaks we
        # know exactly which trials were in it (queued ones were never started).
        in_flight: dict[Future, TrialSpec] = {}
        # Suspects of a crash, each alone in its own one-worker pool.
        isolated: dict[Future, tuple[TrialSpec, ProcessPoolExecutor]] = {}
        # When each running trial started (a pool never holds more trials than workers, so submitted = started).
        started: dict[Future, float] = {}
        try:
            while queue or in_flight or isolated:
                while queue and len(in_flight) < size:
                    try:
                        fut = pool.submit(run_in_worker, queue[0], self.plugins)
                    except BrokenProcessPool:
                        # Broke since the last wait; its in-flight futures fail and are handled below.
                        if not in_flight:
                            pool.shutdown(wait=False, cancel_futures=True)
                            size = min(self.workers, len(queue))
                            pool = self._pool(size)
                            continue
                        break
                    in_flight[fut] = queue.popleft()
                    started[fut] = time.monotonic()
                done, _ = wait([*in_flight, *isolated], return_when=FIRST_COMPLETED, timeout=self._wait_s(started))
                if not done:  # a trial ran past the timeout: kill its pool, record it, restart the innocent
                    expired = self._expired(started)
                    for fut in expired:
                        started.pop(fut)
                        if fut in isolated:
                            spec, solo = isolated.pop(fut)
                            _kill(solo)
                            yield spec, failed_record(spec, TIMED_OUT.format(limit=self.timeout))
                    hung = [f for f in expired if f in in_flight]
                    if hung:
                        queue.extendleft(reversed([sp for f, sp in in_flight.items() if f not in hung]))
                        for f in in_flight:
                            started.pop(f, None)
                        timed_out = [in_flight[f] for f in hung]
                        in_flight.clear()
                        _kill(pool)
                        size = max(1, min(self.workers, len(queue)))
                        pool = self._pool(size)
                        for spec in timed_out:
                            yield spec, failed_record(spec, TIMED_OUT.format(limit=self.timeout))
                    continue
                suspects: list[TrialSpec] = []
                for fut in done:
                    started.pop(fut, None)
                    if fut in isolated:
                        spec, solo = isolated.pop(fut)
                        solo.shutdown(wait=False, cancel_futures=True)
                        yield spec, self._outcome(fut, spec, CRASH_ALONE)
                        continue
                    spec = in_flight.pop(fut)
                    if isinstance(fut.exception(), BrokenProcessPool):
                        suspects.append(spec)
                    else:
                        yield spec, self._outcome(fut, spec, CRASH_ALONE)
                if not suspects:
                    continue
                # The pool is broken: every trial still in it fails too. One suspect is
                # the culprit; several are each rerun alone to find which one crashes.
                suspects.extend(in_flight.values())
                for f in in_flight:
                    started.pop(f, None)
                in_flight.clear()
                pool.shutdown(wait=False, cancel_futures=True)
                if len(suspects) > 1:
                    for spec in suspects:
                        solo = self._pool(1)
                        fut = solo.submit(run_in_worker, spec, self.plugins)
                        isolated[fut] = (spec, solo)
                        started[fut] = time.monotonic()
                size = max(1, min(self.workers, len(queue)))
                pool = self._pool(size)  # starts while the suspects rerun
                if len(suspects) == 1:
                    yield suspects[0], failed_record(suspects[0], CRASH_ONLY.format(exc="BrokenProcessPool"))
        except BaseException:
            # Interrupted (Ctrl-C, generator closed, store error): do not wait for trials
            # that may run for minutes; unrecorded ones simply rerun on resume.
            for p in [pool, *(solo for _, solo in isolated.values())]:
                _kill(p)
            raise
        pool.shutdown(wait=True)

    def _wait_s(self, started: dict[Future, float]) -> float | None:
        """Seconds until the oldest running trial reaches the timeout (None: no timeout)."""
        if self.timeout is None or not started:
            return None
        return max(0.0, min(started.values()) + self.timeout - time.monotonic())

    def _expired(self, started: dict[Future, float]) -> list[Future]:
        now = time.monotonic()
        return [f for f, t in started.items() if self.timeout is not None and now - t >= self.timeout]

    @staticmethod
    def _outcome(fut: Future, spec: TrialSpec, crashed: str) -> TrialRecord:
        exc = fut.exception()
        if exc is None:
            return fut.result()
        if isinstance(exc, BrokenProcessPool):
            return failed_record(spec, crashed.format(exc=str(exc).rstrip(".")))
        # e.g. a record that could not be pickled back: still a recorded failure.
        return failed_record(spec, f"{type(exc).__name__} in worker: {exc}")


@EXECUTORS.register("ray", "one Ray task per trial (local or cluster; pip install 'kintsugi[ray]')")
class RayExecutor:
    """Trial timeout: not enforced (Ray's own task timeouts apply)."""

    def __init__(self, workers: int, plugins: list[str], trial_timeout_s: float | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise KintsugiError(
                "the ray executor needs Ray, which is not installed: pip install 'kintsugi[ray]' "
                "(or use --executor process)"
            ) from None
        self.ray = ray
        self.workers = workers
        self.plugins = list(plugins)

    def run(self, specs: Iterable[TrialSpec]) -> Iterator[tuple[TrialSpec, TrialRecord]]:
        ray = self.ray
        if not ray.is_initialized():
            # Connects to RAY_ADDRESS when set (a cluster), else starts a local one.
            ray.init(ignore_reinit_error=True, log_to_driver=False)
        remote = ray.remote(max_retries=0)(run_in_worker)
        queue = deque(specs)
        # Keep a bounded number of tasks queued so an interrupt cancels little work.
        window = max(self.workers, int(ray.available_resources().get("CPU", self.workers))) * 2
        pending: dict = {}
        try:
            while queue or pending:
                while queue and len(pending) < window:
                    spec = queue.popleft()
                    pending[remote.remote(spec, self.plugins)] = spec
                ready, _ = ray.wait(list(pending), num_returns=1)
                for ref in ready:
                    spec = pending.pop(ref)
                    try:
                        yield spec, ray.get(ref)
                    except Exception as exc:  # noqa: BLE001 - worker died or task failed outside run_trial
                        yield spec, failed_record(spec, f"ray task failed ({type(exc).__name__}): {exc}")
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)


def make_executor(name: str, workers: int, plugins: list[str], trial_timeout_s: float | None = None) -> Executor:
    """Build an executor by registry name (unknown names list the known ones)."""
    return EXECUTORS.get(name).factory(workers, plugins, trial_timeout_s=trial_timeout_s)
