"""Latency of the openai reasoner per role: client overhead (fake local server) or a real endpoint.

    .venv/bin/python bench/bench_reasoner_latency.py               # fake server, client-side cost only
    .venv/bin/python bench/bench_reasoner_latency.py --structured-output text      # text-mode parsing cost
    .venv/bin/python bench/bench_reasoner_latency.py --refuse-strict  # fake server refuses strict options (auto)
    .venv/bin/python bench/bench_reasoner_latency.py --base-url http://localhost:8000/v1 --model Qwen2.5-VL-7B

Images are 640x480 PNGs like the task camera's, so the numbers include PNG
base64 encoding and request size; with a real endpoint they include the model.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import threading
import time
import uuid
from collections import deque
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.reasoning.base import RecordingReasoner  # noqa: E402
from kintsugi.reasoning.openai_backend import OpenAIReasoner  # noqa: E402
from kintsugi.reasoning.roles import ask  # noqa: E402
from kintsugi.methods.recovery import roles  # noqa: E402,F401 - registers judge, analyze and plan
from kintsugi.methods.recovery.types import (  # noqa: E402
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    JudgeRequest,
    PlanRequest,
    SkillOutcome,
)
from kintsugi.perception.types import CameraCalibration, CheckResult, Pose  # noqa: E402


def content(reply: object) -> dict:
    """A scripted assistant reply: dicts are JSON-encoded, strings sent verbatim."""
    return {"content": reply if isinstance(reply, str) else json.dumps(reply)}


def tool_calls(*calls: tuple[str, dict]) -> dict:
    """A scripted reply of tool calls (name, arguments)."""
    return {"content": None, "tool_calls": [
        {"id": f"call_{uuid.uuid4().hex[:12]}", "type": "function", "function": {"name": n, "arguments": json.dumps(a)}}
        for n, a in calls]}


class FakeOpenAIServer:
    """A local chat-completions endpoint on 127.0.0.1 answering scripted replies in order, so the bench measures
    the client's own cost. With `refuse`, it answers HTTP 400 to json_schema or tool_choice=required requests,
    as some local servers do, without consuming a reply."""

    def __init__(self, refuse: tuple[str, ...] | set[str] = ()) -> None:
        self.refuse, self.refused = set(refuse), 0
        self.replies: deque[dict] = deque()
        self.requests: list[dict] = []
        self._httpd = ThreadingHTTPServer(("127.0.0.1", 0), self._handler())
        self._httpd.daemon_threads = True

    @property
    def base_url(self) -> str:
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/v1"

    def push(self, *replies: dict) -> None:
        self.replies.extend(replies)

    def start(self) -> "FakeOpenAIServer":
        threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True).start()
        return self

    def stop(self) -> None:
        self._httpd.shutdown()
        self._httpd.server_close()

    def _refusal(self, body: dict) -> str | None:
        """The error message (worded like local servers') for a request whose strict options this server refuses."""
        if "json_schema" in self.refuse and (body.get("response_format") or {}).get("type") == "json_schema":
            return "response_format type 'json_schema' is not supported by this server; use 'text' or 'json_object'"
        if "tool_choice" in self.refuse and body.get("tool_choice") == "required":
            return "tool_choice 'required' is not supported; only 'auto' and 'none' are"
        return None

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        server = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"
            disable_nagle_algorithm = True  # no 40 ms delayed-ACK stalls per reply

            def log_message(self, *args: object) -> None:
                pass

            def do_POST(self) -> None:  # noqa: N802 - stdlib name
                body = json.loads(self.rfile.read(int(self.headers.get("Content-Length", 0))))
                server.requests.append(body)
                refusal = server._refusal(body)
                if refusal:
                    server.refused += 1
                    status, payload = 400, {"error": {"message": refusal, "type": "invalid_request_error", "code": None}}
                elif server.replies:
                    message = {"role": "assistant", "refusal": None, **server.replies.popleft()}
                    status, payload = 200, {
                        "id": f"chatcmpl-{uuid.uuid4().hex}", "object": "chat.completion", "created": int(time.time()),
                        "model": body.get("model", "fake"),
                        "choices": [{"index": 0, "message": message, "logprobs": None,
                                     "finish_reason": "tool_calls" if message.get("tool_calls") else "stop"}],
                        "usage": {"prompt_tokens": 100, "completion_tokens": 20, "total_tokens": 120}}
                else:
                    status, payload = 500, {"error": {"message": "fake server: no scripted reply left", "type": "bench"}}
                data = json.dumps(payload).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                if status == 500:
                    self.send_header("x-should-retry", "false")
                self.end_headers()
                self.wfile.write(data)

        return Handler


SKILLS = {"fit": ["y"], "align": ["y"], "insert": ["z"]}
GOALS = {"fit": Pose(y=10, z=5), "align": Pose(y=12, z=5), "insert": Pose(y=12, z=-20)}


def camera_png(seed: int) -> bytes:
    """A 640x480 scene-like image: grey background, red rim, green tilted peg, sensor noise."""
    rng = np.random.default_rng(seed)
    img = np.full((480, 640, 3), 200, np.uint8)
    cv2.rectangle(img, (220, 300), (300, 320), (0, 0, 220), -1)
    cv2.rectangle(img, (342, 300), (420, 320), (0, 0, 220), -1)
    box = cv2.boxPoints(((320 + seed % 7, 230), (80, 160), 4.0)).astype(np.int32)
    cv2.fillPoly(img, [box], (0, 200, 0))
    img = cv2.add(img, rng.integers(0, 6, img.shape, dtype=np.uint8))
    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def requests(seed: int) -> tuple[JudgeRequest, AnalyzeRequest, PlanRequest]:
    cal = CameraCalibration(width=640, height=480, px_per_mm=4, cu=320, cv=240, y0_mm=0, z0_mm=0)
    outcome = SkillOutcome(skill="align", goal=GOALS["align"], terminal=Pose(y=11.1, z=4.0), reached_goal=False,
                           timed_out=False, compression_limit=False, image_png=camera_png(seed))
    checks = [CheckResult(name="vision", passed=False, message="p_ey was too small.", measurements={"tilt_deg": 2.0})]
    judge = JudgeRequest(task="insert the round peg", outcome=outcome, checks=checks,
                         success_criteria="peg centred on the hole and within 5 deg of vertical",
                         goal_image_png=camera_png(seed + 1000), calibration=cal)
    verdict = JudgeReply(success=False, explanation="left of hole")
    analyze = AnalyzeRequest(task=judge.task, outcome=outcome, checks=checks, verdict=verdict, goals=GOALS,
                             history=[], calibration=cal, max_step_mm=5, skills=SKILLS)
    analysis = AnalyzeReply(what_happened="-", why="-", how_to_recover="-", restart_from="align",
                            motions=[{"skill": "align", "axis": "y", "delta": 2}])
    plan = PlanRequest(task=judge.task, analysis=analysis, goals=GOALS, skills=SKILLS, max_step_mm=5)
    return judge, analyze, plan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base-url", help="real OpenAI-compatible endpoint; default: local fake server")
    parser.add_argument("--model", default="fake-vlm")
    parser.add_argument("--api-key-env", default="OPENAI_API_KEY")
    parser.add_argument("-n", type=int, default=20, help="calls per role")
    parser.add_argument("--structured-output", choices=("auto", "strict", "text"), default="auto")
    parser.add_argument("--refuse-strict", action="store_true",
                        help="fake server answers HTTP 400 to json_schema and tool_choice=required, like some local servers")
    args = parser.parse_args()

    server = None
    base_url = args.base_url
    if base_url is None:
        server = FakeOpenAIServer(refuse={"json_schema", "tool_choice"} if args.refuse_strict else ()).start()
        base_url = server.base_url
        analysis = AnalyzeReply(what_happened="-", why="-", how_to_recover="-", restart_from="align")
        steps = [{"skill": "align", "goal": {"y": 14.0}}, {"skill": "insert", "goal": {"z": -20.0}}]
        text_plans = args.refuse_strict or args.structured_output == "text"
        for _ in range(args.n):
            server.push(content({"success": False, "explanation": "left of hole"}),
                        content(analysis.model_dump(mode="json")),
                        # text mode: a plan the way small models write it, in a fence with prose around it
                        content("Plan:\n```json\n" + json.dumps({"steps": steps}, indent=2) + "\n```\nDone.")
                        if text_plans else tool_calls(("align", {"y": 14.0}), ("insert", {"z": -20.0})))
    reasoner = RecordingReasoner(OpenAIReasoner(model=args.model, base_url=base_url, api_key_env=args.api_key_env,
                                                timeout_s=120, max_retries=2,
                                                structured_output=args.structured_output))
    try:
        for i in range(args.n):
            judge, analyze, plan = requests(i)
            ask(reasoner, "judge", judge)
            ask(reasoner, "analyze", analyze)
            ask(reasoner, "plan", plan)
    finally:
        if server is not None:
            server.stop()
    print(f"endpoint: {base_url}  model: {args.model}  calls per role: {args.n}  "
          f"structured output: {args.structured_output}{' (server refuses strict)' if args.refuse_strict else ''}")
    print(f"machine: {platform.system()} {platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}")
    if server is not None:
        sizes = [len(str(r)) for r in server.requests]
        print(f"request body chars: median {statistics.median(sizes):.0f}; refused requests: {server.refused}")
    for r in reasoner.records:
        if r.output_note:
            print(f"{r.role}: {r.output_note}")
    print(f"{'role':8} {'median ms':>10} {'p95 ms':>8} {'max ms':>8} {'tokens in':>10} {'tokens out':>10} "
          f"{'attempts':>9} {'mode':>6}")
    for role in ("judge", "analyze", "plan"):
        recs = [r for r in reasoner.records if r.role == role]
        lat = sorted(r.latency_s * 1000 for r in recs)
        p95 = lat[min(len(lat) - 1, int(0.95 * len(lat)))]
        modes = "/".join(sorted({r.output_mode or "-" for r in recs}))
        print(f"{role:8} {statistics.median(lat):10.1f} {p95:8.1f} {lat[-1]:8.1f} "
              f"{sum(r.tokens_in for r in recs) / len(recs):10.0f} {sum(r.tokens_out for r in recs) / len(recs):10.0f} "
              f"{sum(r.attempts for r in recs) / len(recs):9.2f} {modes:>6}")


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"total {time.perf_counter() - t0:.1f} s")
