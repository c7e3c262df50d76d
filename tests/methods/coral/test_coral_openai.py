"""A coral trial over the OpenAI protocol (the local fake server): priors, formulation and adaptation requests
carry the scene camera's image and every object's label and size; the replies plan the trial."""

from __future__ import annotations

import base64
import json

import cv2
import numpy as np

from tests.fake_openai_server import FakeOpenAIServer, content, fake_openai  # noqa: F401
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.runner import run_trial

SHORT = {"control.samples": 16, "control.episode_s": 0.6, "coral.max_attempts": 2}
"""Two short attempts: the first runs out of time, so the outer loop asks the adapt role once."""


def _formulation(task: str) -> dict:
    """The embedded formulation of the task's own first observation (what a model is asked to write)."""
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS
    from kintsugi.methods.coral.costlib import compose
    from kintsugi.methods.coral.method import VARIANTS, Coral

    load_builtins()
    t = TASKS.get(task).factory()
    cfg = t.config(SHORT)
    ep = t.episode(cfg, "default", "none", 0)
    ctx = ep.context(frozenset({"system-c"}), ReasonerSettings(), 0)
    coral = Coral(ctx, VARIANTS["coral"])
    from kintsugi.methods.coral.priors import embedded_priors
    from kintsugi.methods.coral.views import object_views
    from kintsugi.methods.coral.types import PriorsRequest

    priors = embedded_priors(PriorsRequest(task=ctx.task_text, objects=object_views(ctx.known))).objects
    reply = compose(coral.scene_request(ep.robot.observe(), priors))
    return reply.model_dump(mode="json")


def _images(request: dict) -> list[np.ndarray]:
    out = []
    for msg in request["messages"]:
        for part in msg["content"] if isinstance(msg["content"], list) else []:
            if part.get("type") == "image_url":
                data = base64.b64decode(part["image_url"]["url"].split(",", 1)[1])
                out.append(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR))
    return out


def test_a_coral_trial_and_its_adaptation_run_over_the_openai_protocol(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(
        content({"objects": {"box": {"mass_kg": 0.3, "friction": 0.5, "material": "cardboard"}},
                 "reasoning": "a cardboard box of this size"}),
        content(_formulation("flip-box")),
        content({"diagnosis": "the attempt ran out of time; the box is heavier than it looks",
                 "beliefs": {"box": {"mass_kg": 0.4, "friction": 0.6, "material": "cardboard"}}}),
    )
    spec = TrialSpec(task="flip-box", method="coral", variant="default", condition="none", seed=0, overrides=SHORT,
                     reasoner=ReasonerSettings(backend="openai", model="fake-vlm", base_url=fake_openai.base_url,
                                               timeout_s=10.0, max_retries=0))
    rec = run_trial(spec)
    assert rec.error is None, rec.error
    assert [c["role"] for c in rec.transcript] == ["priors", "formulate", "adapt"]
    assert all(c["backend"] == "openai" for c in rec.transcript)
    priors, formulate, adapt = fake_openai.requests[:3]
    for request in (priors, formulate, adapt):
        images = _images(request)
        assert len(images) == 1, "every role is shown the scene camera's image"
        img = images[0]
        assert img.ndim == 3 and img.shape[0] >= 100 and float(img.std()) > 10.0  # a real render, not a blank
    text = json.dumps(priors["messages"])
    assert "box" in text and "size_m" in text
    figures = rec.method_figures
    assert figures["attempts"][0]["beliefs_before"]["box"]["mass_kg"] == 0.3
    assert figures["attempts"][1]["beliefs_before"]["box"]["mass_kg"] == 0.4  # the adapt reply was adopted
