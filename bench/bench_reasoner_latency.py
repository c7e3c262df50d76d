"""Per role of every system: request tokens, reply tokens and seconds, from a real OpenAI-compatible server.

    .venv/bin/python bench/bench_reasoner_latency.py                  # llama-server + the tiny model (make servers)
    .venv/bin/python bench/bench_reasoner_latency.py --server llama-cpp-python
    .venv/bin/python bench/bench_reasoner_latency.py --base-url http://localhost:8000/v1 --model Qwen2.5-VL-7B \
        --images send                                                 # your endpoint, your model

Each role's request is the conformance suite's (`kintsugi/testing/role_requests.py`: a peg judge with its two
camera images, a pour task graph, a CoRAL push scene...). Tokens are the server's own counts (`usage`),
summed over the call's attempts (a repair round is a second attempt); seconds are wall time per call,
median over `--repeat` calls. With the tiny random model the seconds are the server's prompt processing
(and the reply-length cap); with a real model they size the model for a campaign: a peg trial asks judge
5-15 times, AgentChord composer + arranger once, CoRAL priors + formulate once and adapt per failed attempt.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.core.errors import ReasoningError  # noqa: E402
from kintsugi.reasoning.base import RecordingReasoner  # noqa: E402
from kintsugi.reasoning.endpoint_options import OpenAIOptions  # noqa: E402
from kintsugi.reasoning.openai_backend import OpenAIReasoner  # noqa: E402
from kintsugi.reasoning.roles import ask  # noqa: E402
from kintsugi.testing import servers  # noqa: E402
from kintsugi.testing.role_requests import build, system_roles  # noqa: E402


def measure(base_url: str, model: str, roles: list[str], mode: str, images: str, repeat: int,
            max_reply_tokens: int | None) -> list[dict]:
    rows = []
    for role in roles:
        request = build(role)
        tokens_in, tokens_out, seconds, outcomes, attempts = [], [], [], [], []
        for _ in range(repeat):
            rec = RecordingReasoner(OpenAIReasoner(
                model=model, base_url=base_url, timeout_s=300, max_retries=1, structured_output=mode,
                options=OpenAIOptions(images=images, max_reply_tokens=max_reply_tokens, preflight=False)))
            start = time.perf_counter()
            try:
                ask(rec, role, request)
                outcomes.append("ok")
            except ReasoningError as exc:
                outcomes.append(type(exc).__name__)
            seconds.append(time.perf_counter() - start)
            call = rec.records[-1]
            tokens_in.append(call.tokens_in)
            tokens_out.append(call.tokens_out)
            attempts.append(call.attempts)
        rows.append({"role": role, "mode": mode, "tokens_in": statistics.median(tokens_in),
                     "tokens_out": statistics.median(tokens_out), "attempts": statistics.median(attempts),
                     "s": statistics.median(seconds), "outcomes": ",".join(sorted(set(outcomes)))})
    return rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--server", choices=["llama-server", "llama-cpp-python"], default="llama-server",
                   help="which locally built server to start with the tiny model (ignored with --base-url)")
    p.add_argument("--base-url", help="an OpenAI-compatible endpoint to measure instead")
    p.add_argument("--model", default="tiny")
    p.add_argument("--modes", default="strict,text", help="structured-output modes to measure")
    p.add_argument("--images", choices=["send", "measurements"], default="measurements")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--max-reply-tokens", type=int, default=160)
    p.add_argument("--roles", help="comma-separated roles (default: every role of every system)")
    args = p.parse_args()
    known = system_roles()  # registers every role (imports the methods that ask them)
    roles = args.roles.split(",") if args.roles else known
    if unknown := sorted(set(roles) - set(known)):
        sys.exit(f"bench_reasoner_latency: unknown role(s) {', '.join(unknown)}; known: {', '.join(known)}")
    server = None
    if args.base_url is None:
        reason = servers.missing(args.server)
        if reason:
            sys.exit(f"bench_reasoner_latency: {reason}")
        tmp = Path(tempfile.mkdtemp(prefix="kintsugi-bench-"))
        model = servers.tiny_model(tmp / "tiny.gguf")
        start = servers.start_llama_server if args.server == "llama-server" else servers.start_llama_cpp_python
        server = start(model, tmp / "server.log")
        base_url, where = server.base_url, f"{args.server} {servers.VERSION} + tiny random GGUF (1 thread)"
    else:
        base_url, where = args.base_url, args.base_url
    try:
        print(f"# reasoner latency per role: {where}, model {args.model}, images={args.images}, "
              f"max_reply_tokens={args.max_reply_tokens}, median of {args.repeat} ({platform.machine()}, "
              f"{platform.python_version()})")
        print(f"{'role':<10} {'mode':<7} {'tokens in':>9} {'tokens out':>10} {'attempts':>8} {'s/call':>8}  outcome")
        for mode in args.modes.split(","):
            for row in measure(base_url, args.model, roles, mode, args.images, args.repeat, args.max_reply_tokens):
                print(f"{row['role']:<10} {row['mode']:<7} {row['tokens_in']:>9,.0f} {row['tokens_out']:>10,.0f} "
                      f"{row['attempts']:>8.0f} {row['s']:>8.2f}  {row['outcomes']}")
    finally:
        if server is not None:
            server.stop()


if __name__ == "__main__":
    main()
