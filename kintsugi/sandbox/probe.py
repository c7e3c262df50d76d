"""Probe-run model-written cost code in a child process before the control loop uses it.

The child (from a forkserver with this module preloaded, so it inherits no threads or simulator state and
starts in milliseconds) compiles the
source, calls every requested function on sample inputs of the loop's real shapes, and
reports per-call CPU time (the least of a few calls: a loaded machine's waits are not the code's
cost, and CPU time does not count them), output shape and how many values are not finite. It runs under a
CPU-time limit and an address-space limit (RLIMIT_CPU, RLIMIT_AS), and the parent kills it
after a wall-clock timeout. Whatever happens in the child, the parent gets a `ProbeReport`
or one SandboxError saying what went wrong; nothing the code does reaches the parent.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import resource
import time
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from kintsugi.core.errors import SandboxError
from kintsugi.sandbox.program import CostProgram


@dataclass(frozen=True)
class ProbeLimits:
    cpu_s: float = 2.0
    """CPU seconds the child may use in all (compiling, every call)."""
    wall_s: float = 10.0
    """The parent kills the child after this long (covers a child stuck off-CPU)."""
    memory_mb: int = 512
    """Address space the child may add beyond what it starts with."""
    max_call_s: float = 0.05
    """A cost using more CPU time than this per call is refused: the control loop calls it every iteration."""
    repeats: int = 3


@dataclass(frozen=True)
class ProbeReport:
    seconds_per_call: dict[str, float]
    """CPU seconds per call of each probed function (the least of `repeats` calls), measured in the child."""


def _vm_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[0]) * resource.getpagesize()


def _child(conn: Any, source: str, variables: frozenset[str], calls: dict[str, tuple[int, ...]],
           env: dict[str, np.ndarray], limits: ProbeLimits) -> None:
    try:
        used = resource.getrusage(resource.RUSAGE_SELF)
        cpu = math.ceil(used.ru_utime + used.ru_stime + limits.cpu_s)
        resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 1))
        vm = _vm_bytes() + limits.memory_mb * 2**20
        resource.setrlimit(resource.RLIMIT_AS, (vm, vm))
        program = CostProgram.compile(source, variables)
        timings: dict[str, float] = {}
        for name, shape in calls.items():
            samples = []
            for _ in range(limits.repeats):
                t0 = time.thread_time()
                out = program.call(name, env, shape)
                samples.append(time.thread_time() - t0)
            bad = int(np.count_nonzero(~np.isfinite(out)))
            if bad:
                raise SandboxError("non-finite", f"{name}() returns NaN or inf for {bad} of {out.size} values on the "
                                                 f"probe inputs (e.g. sqrt or log of a negative, division by zero)")
            timings[name] = float(min(samples))
        conn.send(("ok", timings))
    except SandboxError as exc:
        conn.send((exc.kind, str(exc)))
    except MemoryError:
        conn.send(("memory", f"cost code ran out of the {limits.memory_mb} MB it may use"))
    except BaseException as exc:  # noqa: BLE001 - report anything; the parent decides
        conn.send(("runtime", f"cost code failed in the probe: {type(exc).__name__}: {exc}"[:400]))
    finally:
        conn.close()


def _context() -> mp.context.BaseContext:
    """The forkserver, with this module preloaded in it: a child forked from a server that has numpy and the
    sandbox imported starts in milliseconds, where one that imports them itself takes about half a second
    (more where bytecode is not cached), twice per formulation. `__main__` stays preloaded as multiprocessing's
    default has it. The list is set before the server starts (setting it later changes nothing). Each child
    still imports the parent's `__main__` script again (multiprocessing's rule for a script run by path), so a
    script that probes keeps its top level light."""
    if "forkserver" not in mp.get_all_start_methods():
        return mp.get_context("spawn")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["__main__", __name__])
    return ctx


def probe(source: str, variables: set[str] | frozenset[str], calls: Mapping[str, tuple[int, ...]],
          env: Mapping[str, np.ndarray], limits: ProbeLimits = ProbeLimits()) -> ProbeReport:
    """Check, compile and run the named functions on `env` in a limited child; raise SandboxError on any failure.

    `calls`: function name -> the output shape the loop expects (e.g. (K,) per rollout).
    The source is checked here first, so syntax and language errors never cost a process.
    """
    program = CostProgram.compile(source, variables)
    missing = [name for name in calls if not program.has(name)]
    if missing:
        raise SandboxError("missing", f"cost code defines no function {missing[0]!r}; it defines: "
                                      f"{', '.join(program.signatures)}")
    ctx = _context()
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, source, frozenset(variables), dict(calls), dict(env), limits),
                       daemon=True)
    proc.start()
    child.close()
    try:
        if not parent.poll(limits.wall_s):
            raise SandboxError("timeout", f"cost code did not finish its probe within {limits.wall_s:g} s")
        try:
            kind, payload = parent.recv()
        except EOFError:
            proc.join(1.0)
            code = proc.exitcode
            what = "its CPU-time limit" if code in (-24, -9) else f"exit code {code}"
            raise SandboxError("killed", f"the probe process died ({what}) while running the cost code") from None
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join(1.0)
        parent.close()
    if kind != "ok":
        raise SandboxError(kind, payload)
    slow = {n: t for n, t in payload.items() if t > limits.max_call_s}
    if slow:
        name, t = max(slow.items(), key=lambda kv: kv[1])
        raise SandboxError("slow", f"{name}() takes {t * 1000:.1f} ms of CPU per call on the probe inputs, more than the "
                                   f"{limits.max_call_s * 1000:g} ms the control loop allows")
    return ProbeReport(seconds_per_call=payload)
