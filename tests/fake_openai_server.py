"""A local HTTP server speaking the OpenAI chat-completions protocol, with scripted replies.

Tests push `Script`s (JSON content, tool calls, HTTP errors, hangs) and then read
`server.requests` to see exactly what the client sent. No test ever needs a real
endpoint. Use it as a context manager or through the `fake_openai` fixture.

Like several local servers, it can refuse the strict structured-output options:
`refuse={"json_schema", "tool_choice"}` answers HTTP `refuse_status` (400) to a
request with `response_format` json_schema or `tool_choice="required"`, without
consuming a script (the refused request is still in `server.requests`).

Like a real server, it answers the backend's capability preflight on its own: a request with a small
`max_tokens` (<= 64; the backend sends none unless `reasoner.options.max_reply_tokens` is set) gets a
short reply (JSON, or a tool call when tools are required), usage counted from the request's size
(85 tokens per image), and lands in `server.probes`, not in `server.requests`; strict options it refuses
are refused there too. `images=False` makes it refuse image inputs as llama.cpp's server does (HTTP 500);
`context=N` refuses probes longer than N tokens as llama.cpp's server does (HTTP 400 naming n_ctx).
"""

from __future__ import annotations

import json
import threading
import time
import uuid
import zlib
from collections import deque
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Iterable, Iterator

import pytest


@dataclass
class Script:
    """One scripted response. Build with the helper functions below."""

    kind: str  # "content" | "tool_calls" | "error" | "hang"
    content: str | None = None
    tool_calls: list[tuple[str, str]] = field(default_factory=list)
    status: int = 200
    retry_after_s: float | None = None
    hang_s: float = 0.0
    usage: tuple[int, int] = (100, 20)
    refusal: str | None = None
    message: str | None = None
    error_fields: dict[str, Any] = field(default_factory=dict)


def content(reply: Any, usage: tuple[int, int] = (100, 20)) -> Script:
    """Assistant text; dicts/lists are JSON-encoded, strings sent verbatim (so malformed JSON works)."""
    text = reply if isinstance(reply, str) else json.dumps(reply)
    return Script("content", content=text, usage=usage)


def tool_calls(*calls: tuple[str, Any], usage: tuple[int, int] = (100, 20)) -> Script:
    """Assistant tool calls (name, arguments); dict arguments are JSON-encoded, strings verbatim."""
    encoded = [(name, args if isinstance(args, str) else json.dumps(args)) for name, args in calls]
    return Script("tool_calls", tool_calls=encoded, usage=usage)


def refusal(text: str) -> Script:
    """A refusal: no content, the reason in `message.refusal` (as OpenAI sends it)."""
    return Script("content", content=None, refusal=text)


def http_error(status: int, retry_after_s: float | None = 0.01, message: str | None = None,
               **error_fields: Any) -> Script:
    """An HTTP error; a small retry-after keeps the client's backoff short in tests. `message` and
    `error_fields` (e.g. llama.cpp's n_ctx, n_prompt_tokens) go into the error object."""
    return Script("error", status=status, retry_after_s=retry_after_s, message=message, error_fields=error_fields)


def hang(seconds: float) -> Script:
    """Accept the request and send nothing for `seconds` (longer than the client timeout)."""
    return Script("hang", hang_s=seconds)


class FakeOpenAIServer:
    """Threaded stdlib HTTP server on 127.0.0.1 with a random free port."""

    def __init__(self, refuse: Iterable[str] = (), refuse_status: int = 400, images: bool = True,
                 context: int | None = None) -> None:
        self.refuse = set(refuse)
        self.context = context
        unknown = self.refuse - REFUSALS.keys()
        if unknown:
            raise ValueError(f"cannot refuse {sorted(unknown)}; known: {sorted(REFUSALS)}")
        self.refuse_status = refuse_status
        self.images = images
        self.probes: list[dict[str, Any]] = []
        self.refused = 0
        self.scripts: deque[Script] = deque()
        self.requests: list[dict[str, Any]] = []
        self.headers: list[dict[str, str]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._httpd = ThreadingHTTPServer(("127.0.0.1", 0), self._handler_class())
        self._httpd.daemon_threads = True
        self._thread = threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True)

    @property
    def base_url(self) -> str:
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/v1"

    def push(self, *scripts: Script) -> None:
        with self._lock:
            self.scripts.extend(scripts)

    def start(self) -> "FakeOpenAIServer":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()  # releases hanging handlers
        self._httpd.shutdown()
        self._httpd.server_close()

    def __enter__(self) -> "FakeOpenAIServer":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _next(self, body: dict[str, Any], headers: dict[str, str]) -> Script | str | None:
        """The script for this request, or the message of a refusal of its strict options."""
        with self._lock:
            self.requests.append(body)
            self.headers.append(headers)
            for option in sorted(self.refuse):
                if REFUSALS[option][0](body):
                    self.refused += 1
                    return REFUSALS[option][1]
            return self.scripts.popleft() if self.scripts else None

    def _probe(self, body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        """A preflight request's answer: (status, payload)."""
        with self._lock:
            self.probes.append(body)
        messages = body.get("messages", [])
        images = sum(1 for m in messages if isinstance(m.get("content"), list)
                     for p in m["content"] if p.get("type") == "image_url")
        if images and not self.images:
            return 500, {"error": {"code": 500, "message": "image input is not supported - hint: if this is "
                                   "unexpected, you may need to provide the mmproj", "type": "server_error"}}
        for option in sorted(self.refuse):
            if REFUSALS[option][0](body):
                return self.refuse_status, {"error": {"message": REFUSALS[option][1], "type": "invalid_request_error"}}
        text = json.dumps([m.get("content") for m in messages if isinstance(m.get("content"), str)])
        text += json.dumps([p.get("text", "") for m in messages if isinstance(m.get("content"), list)
                            for p in m["content"]])
        script = tool_calls(("probe", {"ok": True})) if body.get("tool_choice") == "required" else content({"ok": True})
        script.usage = (len(text) // 4 + 85 * images, 1)
        if self.context is not None and script.usage[0] > self.context:
            return 400, {"error": {"code": 400, "message": "the request exceeds the available context size, try "
                                   "increasing it", "type": "exceed_context_size_error",
                                   "n_prompt_tokens": script.usage[0], "n_ctx": self.context}}
        return 200, _completion(body, script)

    def _handler_class(self) -> type[BaseHTTPRequestHandler]:
        server = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"
            disable_nagle_algorithm = True  # no 40 ms delayed-ACK stalls per reply

            def log_message(self, *args: Any) -> None:  # keep test output clean
                pass

            def _send(self, status: int, payload: dict[str, Any], extra: dict[str, str] | None = None) -> None:
                data = json.dumps(payload).encode()
                try:
                    self.send_response(status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    for k, v in (extra or {}).items():
                        self.send_header(k, v)
                    self.end_headers()
                    self.wfile.write(data)
                except (BrokenPipeError, ConnectionResetError):
                    pass  # the client gave up (timeout); nothing to do

            def do_POST(self) -> None:  # noqa: N802 - stdlib name
                length = int(self.headers.get("Content-Length", 0))
                raw = self.rfile.read(length)
                if self.path.rstrip("/") == "/v1/embeddings":
                    body = json.loads(raw)
                    server.requests.append(body)
                    self._send(200, _embeddings(body))
                    return
                if self.path.rstrip("/") != "/v1/chat/completions":
                    self._send(404, {"error": {"message": f"no route {self.path}", "type": "not_found"}})
                    return
                try:
                    body = json.loads(raw)
                except json.JSONDecodeError:
                    self._send(400, {"error": {"message": "body is not JSON", "type": "invalid_request_error"}})
                    return
                if isinstance(body.get("max_tokens"), int) and body["max_tokens"] <= PROBE_MAX_TOKENS:
                    status, payload = server._probe(body)
                    self._send(status, payload)
                    return
                script = server._next(body, {k.lower(): v for k, v in self.headers.items()})
                if isinstance(script, str):
                    self._send(server.refuse_status, {"error": {"message": script, "type": "invalid_request_error",
                                                                "code": None}})
                    return
                if script is None:
                    # fail loudly and tell the SDK not to retry, so a missing script is obvious
                    self._send(500, {"error": {"message": "fake server: no scripted reply left", "type": "test"}},
                               {"x-should-retry": "false"})
                    return
                if script.kind == "hang":
                    server._stop.wait(script.hang_s)
                    self.close_connection = True
                    return
                if script.kind == "error":
                    extra = {}
                    if script.retry_after_s is not None:
                        extra["retry-after-ms"] = str(int(script.retry_after_s * 1000) or 1)
                        extra["retry-after"] = str(script.retry_after_s)
                    error = {"message": script.message or f"scripted HTTP {script.status}", "type": "server_error",
                             "code": None, **script.error_fields}
                    self._send(script.status, {"error": error}, extra)
                    return
                self._send(200, _completion(body, script))

        return Handler


PROBE_MAX_TOKENS = 64
"""Requests with at most this many `max_tokens` are the backend's preflight probes."""

REFUSALS = {
    "json_schema": (
        lambda body: (body.get("response_format") or {}).get("type") == "json_schema",
        "response_format type 'json_schema' is not supported by this server; use 'text' or 'json_object'",
    ),
    "tool_choice": (
        lambda body: body.get("tool_choice") == "required",
        "tool_choice 'required' is not supported; only 'auto' and 'none' are",
    ),
}
"""What `refuse` can name: a test on the request body, and the error message (worded like local servers')."""


def _embeddings(body: dict[str, Any]) -> dict[str, Any]:
    """Deterministic stand-in embeddings: a hashed bag of words (64 dims), so texts sharing words are close."""
    texts = body["input"] if isinstance(body["input"], list) else [body["input"]]
    data = []
    for i, text in enumerate(texts):
        vec = [0.0] * 64
        for word in str(text).lower().split():
            vec[zlib.crc32(word.encode()) % 64] += 1.0
        data.append({"object": "embedding", "index": i, "embedding": vec})
    return {"object": "list", "data": data, "model": body.get("model", "fake"),
            "usage": {"prompt_tokens": 1, "total_tokens": 1}}


def _completion(body: dict[str, Any], script: Script) -> dict[str, Any]:
    message: dict[str, Any] = {"role": "assistant", "content": script.content, "refusal": script.refusal}
    finish = "stop"
    if script.kind == "tool_calls":
        message["content"] = None
        message["tool_calls"] = [
            {"id": f"call_{uuid.uuid4().hex[:12]}", "type": "function", "function": {"name": n, "arguments": a}}
            for n, a in script.tool_calls
        ]
        finish = "tool_calls"
    prompt, completion = script.usage
    return {
        "id": f"chatcmpl-{uuid.uuid4().hex}",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": body.get("model", "fake"),
        "choices": [{"index": 0, "message": message, "finish_reason": finish, "logprobs": None}],
        "usage": {"prompt_tokens": prompt, "completion_tokens": completion, "total_tokens": prompt + completion},
    }


@pytest.fixture
def fake_openai() -> Iterator[FakeOpenAIServer]:
    """A running fake server, stopped after the test."""
    with FakeOpenAIServer() as server:
        yield server
