"""One chat-completions request: retried only when a retry can help, and errors that say what the endpoint
cannot do.

Real servers refuse things in different ways: a strict option (`response_format` json_schema,
`tool_choice`) as HTTP 400, 422 or 500 with a message naming it; images as "image input is not supported"
(HTTP 500 from llama.cpp's server); a long request as a 400 naming the context. Each is recognized by its
message whatever the status, and none is retried (it would fail the same way). Timeouts, dropped
connections, 408/409/429 and other 5xx are retried with backoff (honouring Retry-After).
"""

from __future__ import annotations

import json
import re
import time
from typing import Any, Callable

import openai

from kintsugi.core.errors import ReasoningError

STRICT_OPTION_WORDS = re.compile(r"response.?format|json.?schema|tool.?choice|\btools?\b|function.?call", re.I)
"""An error naming one of these (to a request that sent strict options) refuses those options."""
IMAGE_WORDS = re.compile(r"\bimages?\b|image.?url|vision|multi.?modal|mmproj", re.I)
CONTEXT_WORDS = re.compile(r"context.?(size|length|window)|maximum context|too many tokens|prompt is too long|"
                           r"exceed\w* the (available )?context", re.I)
RETRIABLE_STATUS = frozenset({408, 409, 429, 500, 502, 503, 504})
BACKOFF_S = (0.5, 1.0, 2.0, 4.0, 8.0)
MAX_RETRY_AFTER_S = 60.0


class EndpointError(ReasoningError):
    """The endpoint could not be used (unreachable, timeout, HTTP error), after any retry that could help."""


class ImagesRefused(EndpointError):
    """The endpoint does not take image inputs."""


class ContextTooLong(EndpointError):
    """A request did not fit the model's context; `n_ctx` / `n_prompt` when the server said them."""

    def __init__(self, message: str, n_ctx: int | None = None, n_prompt: int | None = None) -> None:
        super().__init__(message)
        self.n_ctx = n_ctx
        self.n_prompt = n_prompt


class Refused(Exception):
    """The server refused the strict options of one request (the caller switches to text or reports it)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def shorten(text: str, limit: int = 300) -> str:
    text = re.sub(r"^Error code: \d+ - ", "", " ".join(str(text).split()))
    return text if len(text) <= limit else text[: limit - 3] + "..."


def error_text(exc: openai.APIStatusError) -> str:
    """The status error's message and body, as one searchable string."""
    body = json.dumps(exc.body, default=str) if exc.body is not None else ""
    return f"{exc.message} {body}"


def context_numbers(exc: openai.APIStatusError) -> tuple[int | None, int | None]:
    """(context tokens, prompt tokens) from a context-length refusal, as far as the server says them."""
    body = exc.body if isinstance(exc.body, dict) else {}
    inner = body.get("error", body) if isinstance(body.get("error", body), dict) else body
    n_ctx = inner.get("n_ctx") if isinstance(inner.get("n_ctx"), int) else None
    n_prompt = inner.get("n_prompt_tokens") if isinstance(inner.get("n_prompt_tokens"), int) else None
    text = error_text(exc)
    m = re.search(r"maximum context length is (\d+)", text)
    if m and n_ctx is None:
        n_ctx = int(m.group(1))
    m = re.search(r"\((\d+) in (?:the messages|your prompt)", text) or \
        re.search(r"(?:requested|resulted in|prompt (?:has|is)) (\d+) tokens", text)
    if m and n_prompt is None:
        n_prompt = int(m.group(1))
    return n_ctx, n_prompt


def describe_messages(messages: list[dict[str, Any]]) -> str:
    """Where a request's size is: characters of each message's text, and its images."""
    parts = []
    for m in messages:
        content = m.get("content")
        if isinstance(content, str) or content is None:
            chars, images = len(content or ""), 0
        else:
            chars = sum(len(p.get("text", "")) for p in content if p.get("type") == "text")
            images = sum(1 for p in content if p.get("type") == "image_url")
        parts.append(f"{m['role']} {chars:,} chars" + (f" + {images} image(s)" if images else ""))
    return ", ".join(parts)


def _retry_after(exc: openai.APIStatusError) -> float | None:
    headers = getattr(getattr(exc, "response", None), "headers", None) or {}
    for key, scale in (("retry-after-ms", 0.001), ("retry-after", 1.0)):
        try:
            value = float(headers.get(key)) * scale
        except (TypeError, ValueError):
            continue
        if 0 <= value <= MAX_RETRY_AFTER_S:
            return value
    return None


def send(client: Any, model: str, messages: list[dict[str, Any]], options: dict[str, Any], *, where: str,
         timeout_s: float, max_retries: int, what: str = "this request",
         sleep: Callable[[float], None] = time.sleep) -> Any:
    """`client.chat.completions.create(...)` -> the completion; raises `Refused` (strict options refused),
    `ImagesRefused`, `ContextTooLong` or `EndpointError`. `client` must not retry by itself."""
    last: EndpointError | None = None
    for attempt in range(max_retries + 1):
        wait = BACKOFF_S[min(attempt, len(BACKOFF_S) - 1)]
        try:
            return client.chat.completions.create(model=model, messages=messages, **options)
        except openai.APITimeoutError:
            last = EndpointError(f"no reply from {where} within {timeout_s:g} s (tried {attempt + 1} time(s)); "
                                 f"raise reasoner.timeout_s or check that the server is not overloaded")
        except openai.APIConnectionError as exc:
            last = EndpointError(f"cannot reach {where} ({exc}); is the server running and the URL right?")
        except openai.AuthenticationError:
            raise EndpointError(f"{where} rejected the API key; check the env var named by reasoner.api_key_env") from None
        except openai.NotFoundError as exc:
            raise EndpointError(f"{where} does not know model {model!r} ({shorten(exc.message)}); set reasoner.model") from None
        except openai.APIStatusError as exc:
            status, text = exc.status_code, error_text(exc)
            head = f"{where} answered HTTP {status}: {shorten(exc.message)}"
            if options.keys() & {"response_format", "tools", "tool_choice"} and STRICT_OPTION_WORDS.search(text) \
                    and not CONTEXT_WORDS.search(text):
                raise Refused(f"HTTP {status}: {shorten(exc.message)}") from None
            if CONTEXT_WORDS.search(text):
                n_ctx, n_prompt = context_numbers(exc)
                size = (f"the request is {n_prompt:,} tokens" if n_prompt else "the request is too long") + \
                       (f" against the model's {n_ctx:,}-token context" if n_ctx else "")
                raise ContextTooLong(f"{head}; {size} ({what}: {describe_messages(messages)}); use a model with a "
                                     f"longer context (or start the server with a larger one)", n_ctx, n_prompt) from None
            if IMAGE_WORDS.search(text) and _has_images(messages):
                raise ImagesRefused(f"{head}; this endpoint takes no images and {what} sends camera images: use a "
                                    f"vision model, or --set reasoner.options.images=measurements") from None
            if status not in RETRIABLE_STATUS or _no_retry(exc):
                hint = "; try --structured-output text" if status in (400, 422) and options else ""
                raise EndpointError(head + hint) from None
            last = EndpointError(head + (f" (tried {attempt + 1} times)" if attempt else ""))
            wait = _retry_after(exc) if _retry_after(exc) is not None else wait
        except openai.APIError as exc:
            raise EndpointError(f"{where} returned an unusable response: {exc}") from None
        if attempt < max_retries:
            sleep(wait)
    assert last is not None
    raise last


def _no_retry(exc: openai.APIStatusError) -> bool:
    headers = getattr(getattr(exc, "response", None), "headers", None) or {}
    return str(headers.get("x-should-retry", "")).lower() == "false"


def _has_images(messages: list[dict[str, Any]]) -> bool:
    return any(isinstance(m.get("content"), list) and any(p.get("type") == "image_url" for p in m["content"])
               for m in messages)
