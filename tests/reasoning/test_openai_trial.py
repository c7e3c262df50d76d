"""A whole recovery trial driven by the openai backend, against the local fake OpenAI server."""

from __future__ import annotations

from tests.fake_openai_server import FakeOpenAIServer, content, fake_openai, tool_calls  # noqa: F401
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.recovery.skill_log import PegFigures

ANALYSIS = {"what_happened": "fit judged failed", "why": "scripted", "how_to_recover": "retry fit",
            "restart_from": "fit", "motions": [{"skill": "fit", "axis": "y", "delta": 0.0}]}


def _spec(server: FakeOpenAIServer) -> TrialSpec:
    return TrialSpec(task="peg-insertion", method="recovery", variant="square", condition="none", seed=0,
                     reasoner=ReasonerSettings(backend="openai", model="scripted", base_url=server.base_url,
                                               timeout_s=5.0, max_retries=0))


def test_recovery_trial_over_the_openai_protocol(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(
        content({"success": False, "explanation": "tip not in the hole"}),  # judge fit
        content(ANALYSIS),  # analyze
        tool_calls(("fit", {"y": 1.5}), ("align", {"y": -1.0}), ("insert", {"z": 115.0})),  # plan
        content({"success": True, "explanation": "fit ok"}),
        content({"success": True, "explanation": "align ok"}),
        content({"success": True, "explanation": "insert ok"}),
    )
    rec = run_trial(_spec(fake_openai))
    assert rec.error is None
    assert rec.success and rec.framework_success
    assert [c["role"] for c in rec.transcript] == ["judge", "analyze", "plan", "judge", "judge", "judge"]
    assert all(c["backend"] == "openai" and c["tokens_in"] > 0 and c["latency_s"] > 0 for c in rec.transcript)
    assert rec.transitions == [("fit", "fit")] and PegFigures.of(rec).extra_executions["fit"] == 1
    first = fake_openai.requests[0]["messages"][-1]["content"]
    assert any(part.get("type") == "image_url" and part["image_url"]["url"].startswith("data:image/png;base64,")
               for part in first if isinstance(part, dict))


def test_unusable_plans_end_the_trial_with_a_recorded_reasoning_error(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(
        content({"success": False, "explanation": "tip not in the hole"}),
        content(ANALYSIS),
        tool_calls(("teleport", {"y": 0.0})),  # unknown skill
        tool_calls(("teleport", {"y": 0.0})),  # still unknown after the repair round
    )
    rec = run_trial(_spec(fake_openai))
    assert rec.error is not None and "teleport" in rec.error
    assert not rec.framework_success
    assert rec.reasoning_errors == 1 and rec.transcript[-1]["role"] == "plan"
