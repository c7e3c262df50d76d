"""Campaigns through the `openai` backend against real servers, in worker processes: the preflight runs once in
the campaign's process, and what it learnt reaches the trials (their calls say which options were in effect)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.testing.servers import Server


def bench(server: Server, out: Path, task: str, method: str, variant: str, condition: str, *extra: str):
    from kintsugi.cli import app

    return CliRunner().invoke(app, [
        "bench", task, "--methods", method, "--shapes", variant, "--conditions", condition, "--trials", "1",
        "--workers", "1", "--reasoner", "openai", "--model", "tiny", "--base-url", server.base_url,
        "--set", "reasoner.max_retries=1", "--set", "reasoner.options.max_reply_tokens=160",
        "--set", "reasoner.options.images=measurements", *extra, "--out", str(out)])


def records(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines() if line.strip()]


@pytest.mark.slow
def test_a_peg_campaign_runs_with_measurements_instead_of_images_on_llama_server(llama_server: Server,
                                                                                 tmp_path: Path) -> None:
    out = tmp_path / "peg"
    result = bench(llama_server, out, "peg-insertion", "recovery", "square", "none")
    assert result.exit_code in (0, 1), result.output
    (record,) = records(out)
    assert record["reasoning_calls"] >= 1 and record["reasoning_calls"] == len(record["transcript"])
    for call in record["transcript"]:
        assert call["backend"] == "openai" and call["images_sent"] == 0
        assert (call["reply"] is None) != (call["error"] is None), call
    assert record["transcript"][0]["images_withheld"] > 0  # the judge's camera images, withheld and counted
    if record["error"] is not None:  # a recorded reasoning error of the random model, never a crash
        assert "Traceback" not in record["error"] and "Error" in record["error"].splitlines()[0]


@pytest.mark.slow
def test_a_campaign_on_llama_cpp_python_learns_once_and_its_trials_start_in_text_mode(llama_cpp_python: Server,
                                                                                     tmp_path: Path) -> None:
    out = tmp_path / "peg"
    before = llama_cpp_python.log.read_text(errors="replace").count("500 Internal Server Error")
    result = bench(llama_cpp_python, out, "peg-insertion", "recovery", "square", "none")
    assert result.exit_code in (0, 1), result.output
    said = " ".join(result.output.split())
    assert "does not honour strict response_format json_schema" in said and "will ask for JSON in text" in said
    refusals = llama_cpp_python.log.read_text(errors="replace").count("500 Internal Server Error") - before
    # only the preflight's probes: the image probe (list-form content, a 500 tried twice) and strict json_schema;
    # no trial request is refused again
    assert refusals == 3
    (record,) = records(out)
    assert record["transcript"], record["error"]
    for call in record["transcript"]:
        assert call["output_mode"] == "text", call
        assert "text mode from the preflight" in (call["output_note"] or ""), call
        assert call["error"] is None or "EndpointError" not in call["error"], call["error"]
