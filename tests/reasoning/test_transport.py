"""What real servers answer, played by the fake server: refusals at any status, images refused, contexts
exceeded, each recognized by its message and never retried; transient errors retried."""

from __future__ import annotations

import pytest

from tests.fake_openai_server import FakeOpenAIServer, content, http_error
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.endpoint_options import OpenAIOptions
from kintsugi.reasoning.openai_backend import OpenAIReasoner
from kintsugi.reasoning.roles import ask
from kintsugi.reasoning.transport import ContextTooLong, EndpointError, ImagesRefused
from kintsugi.methods.recovery import roles  # noqa: F401 - registers judge, analyze and plan
from kintsugi.testing.peg_requests import judge_request

JUDGE_OK = {"success": True, "explanation": "seated"}


def make(server: FakeOpenAIServer, images: str = "send", retries: int = 2) -> OpenAIReasoner:
    return OpenAIReasoner(model="m", base_url=server.base_url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY", timeout_s=5,
                          max_retries=retries, options=OpenAIOptions(images=images))


@pytest.mark.parametrize("status", [400, 422, 500])
def test_a_refused_json_schema_switches_auto_to_text_whatever_the_status(status: int) -> None:
    with FakeOpenAIServer(refuse={"json_schema"}, refuse_status=status) as server:
        server.push(content(JUDGE_OK))
        rec = RecordingReasoner(make(server))
        assert ask(rec, "judge", judge_request()).success
        assert server.refused == 1 and len(server.requests) == 2  # the refusal was not retried
        assert rec.records[0].output_mode == "text" and f"HTTP {status}" in rec.records[0].output_note


def test_images_refused_is_one_clear_error_not_retried(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(500, message="image input is not supported - hint: if this is unexpected, you may "
                                             "need to provide the mmproj"))
    with pytest.raises(ImagesRefused, match="takes no images and the judge request sends camera images: use a "
                                            "vision model, or --set reasoner.options.images=measurements"):
        ask(make(fake_openai), "judge", judge_request())
    assert len(fake_openai.requests) == 1


def test_measurements_instead_of_images_are_labelled_in_the_record(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content(JUDGE_OK))
    rec = RecordingReasoner(make(fake_openai, images="measurements"))
    assert not rec.sees_images
    ask(rec, "judge", judge_request())
    sent = fake_openai.requests[0]["messages"][-1]["content"]
    assert isinstance(sent, str) and "image withheld" in sent and "image_url" not in sent
    assert rec.records[0].images_withheld == 2 and rec.records[0].images_sent == 0


def test_a_request_over_the_context_names_its_size_and_parts(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(400, message="the request exceeds the available context size, try increasing it",
                                type="exceed_context_size_error", n_prompt_tokens=9786, n_ctx=2048))
    with pytest.raises(ContextTooLong, match=r"the request is 9,786 tokens against the model's 2,048-token context "
                                             r"\(the judge request: system [\d,]+ chars, user [\d,]+ chars \+ 2 image"):
        ask(make(fake_openai), "judge", judge_request())
    assert len(fake_openai.requests) == 1


def test_openai_style_context_errors_are_read_too(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(400, message="This model's maximum context length is 8192 tokens. However, you "
                                             "requested 9000 tokens (8000 in the messages, 1000 in the completion)."))
    with pytest.raises(ContextTooLong) as info:
        ask(make(fake_openai), "judge", judge_request())
    assert (info.value.n_ctx, info.value.n_prompt) == (8192, 8000)  # the prompt's tokens, not the reply's


def test_transient_errors_are_retried_with_the_count_in_the_message(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(503), http_error(503), http_error(503))
    with pytest.raises(EndpointError, match=r"HTTP 503.*tried 3 times"):
        ask(make(fake_openai), "judge", judge_request())
    assert len(fake_openai.requests) == 3


def test_images_are_scaled_to_the_roles_need(fake_openai: FakeOpenAIServer) -> None:
    import base64

    import cv2
    import numpy as np

    from kintsugi.reasoning.images import png_size

    big = cv2.imencode(".png", np.full((480, 640, 3), 90, np.uint8))[1].tobytes()
    request = judge_request()
    request = request.model_copy(update={"outcome": request.outcome.model_copy(update={"image_png": big})})
    fake_openai.push(content(JUDGE_OK))
    ask(make(fake_openai), "judge", request)
    parts = fake_openai.requests[0]["messages"][-1]["content"]
    urls = [p["image_url"]["url"] for p in parts if p.get("type") == "image_url"]
    sizes = [png_size(base64.b64decode(u.split(",", 1)[1])) for u in urls]
    assert (512, 384) in sizes
    assert any("scaled by 0.8 from the 640x480 px camera image" in p.get("text", "") for p in parts)
