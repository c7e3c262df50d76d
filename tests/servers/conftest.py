"""Session fixtures: the tiny model and the real servers serving it (`make servers` builds them once per
machine; `make test-servers` builds them and runs this suite).

The suite runs when KINTSUGI_REAL_SERVERS=1 (set by `make test` and `make test-servers`); otherwise, and where
this machine cannot build the servers, it skips with the reason."""

from __future__ import annotations

import os

from pathlib import Path
from typing import Iterator

import pytest

from kintsugi.testing.servers import Server, missing, start_llama_cpp_python, start_llama_server, tiny_model

LARGE_CONTEXT = 32768
SMALL_CONTEXT = 2048


def _need(what: str) -> None:
    if os.environ.get("KINTSUGI_REAL_SERVERS") != "1":
        pytest.skip("the real-server suite runs with KINTSUGI_REAL_SERVERS=1: `make test-servers`")
    reason = missing(what)
    if reason:
        pytest.skip(reason)


@pytest.fixture(scope="session")
def tiny_gguf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    _need("gguf")
    return tiny_model(tmp_path_factory.mktemp("model") / "tiny.gguf", context=LARGE_CONTEXT)


def _serve(start, model: Path, tmp: Path, context: int) -> Iterator[Server]:
    server = start(model, tmp / "server.log", context=context)
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture(scope="session")
def llama_server(tiny_gguf: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """llama.cpp's server with a 32k context (the requests of every role fit; AgentChord's composer is ~30k tokens)."""
    _need("llama-server")
    yield from _serve(start_llama_server, tiny_gguf, tmp_path_factory.mktemp("llama-server"), LARGE_CONTEXT)


@pytest.fixture(scope="session")
def llama_server_small(tiny_gguf: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """The same model served with a 2,048-token context."""
    _need("llama-server")
    yield from _serve(start_llama_server, tiny_gguf, tmp_path_factory.mktemp("llama-small"), SMALL_CONTEXT)


@pytest.fixture(scope="session")
def llama_cpp_python(tiny_gguf: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """llama-cpp-python's own server (refuses strict json_schema with HTTP 500)."""
    _need("llama-cpp-python")
    yield from _serve(start_llama_cpp_python, tiny_gguf, tmp_path_factory.mktemp("llama-cpp-python"), LARGE_CONTEXT)
