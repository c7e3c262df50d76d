"""Real OpenAI-compatible servers for conformance checks: llama.cpp's `llama-server` and llama-cpp-python's
server, both built once per machine from the pinned llama-cpp-python source package (`make servers` runs
tests/servers/prepare.sh: `build_llama_server.sh` compiles llama.cpp once, as shared libraries;
`build_tools.sh` installs llama-cpp-python on them), serving a tiny generated GGUF model (`tiny_gguf.py`
beside this module) on 127.0.0.1. Each server is started on a free port and stopped by its process id."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
PACKAGE = HERE.parent
VERSION = os.environ.get("LLAMA_CPP_PYTHON_VERSION", "0.3.36")
CACHE = Path(os.environ.get("KINTSUGI_CACHE", Path.home() / ".cache" / "kintsugi")) / f"llama-cpp-python-{VERSION}"
LLAMA_SERVER = CACHE / "bin" / "llama-server"
TOOLS_PYTHON = CACHE / "venv" / "bin" / "python"
TOOLS_OK = CACHE / "venv" / ".kintsugi-llama-cpp-python-ok"
"""Written by tests/servers/build_tools.sh once llama-cpp-python is installed on llama-server's shared libraries."""
GGUF_OK = CACHE / "venv" / ".kintsugi-gguf-ok"
UNAVAILABLE = CACHE / "unavailable.txt"
"""Written by `make servers` when this machine cannot build the servers (no compiler, no cmake): the reason."""
PROMPTS = sorted(PACKAGE.glob("methods/*/prompts/*.md"))
"""The prompt files whose words make the tiny model's vocabulary."""
START_TIMEOUT_S = 60.0


def missing(what: str) -> str | None:
    """Why `what` ('gguf', 'llama-server' or 'llama-cpp-python') cannot be used here, or None when it can."""
    if UNAVAILABLE.exists():
        return f"the real-server build is impossible on this machine: {UNAVAILABLE.read_text().strip()}"
    if what == "llama-server" and not (LLAMA_SERVER.exists() and (LLAMA_SERVER.parent / "libllama.so").exists()):
        return f"{LLAMA_SERVER} is not built; run `make servers` (tests/servers/build_llama_server.sh)"
    if not GGUF_OK.exists():
        return f"the servers' tool venv {CACHE / 'venv'} has no gguf; run `make servers` (tests/servers/build_tools.sh)"
    if what == "llama-cpp-python" and not TOOLS_OK.exists():
        return f"the servers' tool venv {CACHE / 'venv'} is not built; run `make servers` (tests/servers/build_tools.sh)"
    return None


def tiny_model(out: Path, context: int = 32768, seed: int = 0) -> Path:
    """Write the tiny GGUF model (its vocabulary from the methods' prompt files) with the tool venv's `gguf`,
    running `tiny_gguf.py` as a script (the main environment needs no `gguf`)."""
    subprocess.run([str(TOOLS_PYTHON), str(HERE / "tiny_gguf.py"), str(out), "--context", str(context),
                    "--seed", str(seed), "--words", *map(str, PROMPTS)], check=True, capture_output=True, timeout=120)
    return out


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Server:
    """A running server process; `base_url` ends in /v1."""

    name: str
    process: subprocess.Popen
    port: int
    log: Path

    @property
    def base_url(self) -> str:
        return f"http://127.0.0.1:{self.port}/v1"

    def get(self, path: str) -> object:
        with urllib.request.urlopen(f"http://127.0.0.1:{self.port}{path}", timeout=10) as r:  # noqa: S310 - local
            return json.loads(r.read())

    def stop(self) -> None:
        """Stop by process id: SIGTERM, then SIGKILL after 10 s."""
        if self.process.poll() is None:
            os.kill(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.kill(self.process.pid, signal.SIGKILL)
                self.process.wait(timeout=10)


def _start(name: str, cmd: list[str], port: int, log: Path, ready: str) -> Server:
    handle = log.open("wb")
    process = subprocess.Popen(cmd, stdout=handle, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                               env={**os.environ, "OMP_NUM_THREADS": "1"})
    server = Server(name, process, port, log)
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"{name} exited with {process.returncode}: {log.read_text()[-2000:]}")
        try:
            server.get(ready)
            return server
        except (OSError, ValueError):
            time.sleep(0.1)
    server.stop()
    raise RuntimeError(f"{name} did not answer {ready} within {START_TIMEOUT_S:g} s: {log.read_text()[-2000:]}")


def start_llama_server(model: Path, log: Path, context: int = 32768) -> Server:
    port = free_port()
    cmd = [str(LLAMA_SERVER), "-m", str(model), "--host", "127.0.0.1", "--port", str(port), "--jinja",
           "-c", str(context), "-np", "1", "-t", "1", "--seed", "0", "--alias", "tiny"]
    return _start("llama-server", cmd, port, log, "/health")


def start_llama_cpp_python(model: Path, log: Path, context: int = 32768) -> Server:
    port = free_port()
    cmd = [str(TOOLS_PYTHON), "-m", "llama_cpp.server", "--model", str(model), "--host", "127.0.0.1",
           "--port", str(port), "--n_ctx", str(context), "--n_threads", "1", "--seed", "0",
           "--model_alias", "tiny"]
    return _start("llama-cpp-python", cmd, port, log, "/v1/models")
