"""The probe's child process: forked from a server that has the sandbox imported already."""

from __future__ import annotations

import importlib
from multiprocessing import forkserver

import numpy as np
import pytest

from kintsugi.sandbox import probe

probe_module = importlib.import_module("kintsugi.sandbox.probe")  # the package exports a function by this name


def test_the_forkserver_preloads_the_sandbox_and_keeps_main() -> None:
    ctx = probe_module._context()
    if ctx.get_start_method() != "forkserver":
        pytest.skip("this platform has no forkserver; children are spawned")
    preload = forkserver._forkserver._preload_modules
    assert "kintsugi.sandbox.probe" in preload
    assert "__main__" in preload  # multiprocessing's own default stays


def test_probes_run_one_after_another_from_the_preloaded_server() -> None:
    env = {"x": np.linspace(0.0, 1.0, 8)}
    for scale in (1.0, 2.0, 3.0):
        report = probe(f"def cost(x):\n    return {scale} * x\n", {"x"}, {"cost": (8,)}, env)
        assert set(report.seconds_per_call) == {"cost"}
