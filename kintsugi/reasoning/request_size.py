"""Does each role's real first request fit the model's context? The endpoint counts it.

The preflight captures the first request each role of a method sends on the campaign's first trial
(`first_requests`: built from a real first observation, images at the size sent, in the output mode in
effect) and asks the endpoint to count it (a one-token completion; the server reports the prompt's
tokens, or refuses it naming the context). A request that does not fit stops the campaign with one line
saying how large each part is (system prompt, role prompt, request data, answer format or tool
definitions, images), the largest first.
"""

from __future__ import annotations

from typing import Any, Callable

from kintsugi.reasoning.first_requests import first_requests
from kintsugi.reasoning.transport import ContextTooLong, EndpointError, Refused

Count = Callable[[list[dict[str, Any]], dict[str, Any]], Any]
"""(messages, options) -> the endpoint's completion of one token (its usage counts the prompt)."""


class TooLong(Exception):
    """A first request does not fit; the message is the campaign's one-line reason."""


def check_first_requests(count: Count, spec: Any, method: str, role_names: list[str], n_ctx: int | None,
                         n_ctx_source: str, reply_tokens: int, label: str) -> tuple[list[str], set[str]]:
    """(notes, the roles whose first request was counted); raises TooLong."""
    outgoing, problem = first_requests(spec, role_names)
    notes = []
    if set(role_names) - set(outgoing):
        missing = ", ".join(sorted(set(role_names) - set(outgoing)))
        notes.append(f"{method}'s {missing}: not asked in the dry run of {spec.key} "
                     f"({problem or 'the trial ended without asking'}); only their prompts are counted")
    for name, out in outgoing.items():
        tokens, refused_ctx, refused = _tokens(count, out.messages, out.options)
        ctx = refused_ctx or n_ctx
        if not refused and (tokens is None or ctx is None or tokens + reply_tokens <= ctx):
            if tokens is not None and ctx is not None and tokens + reply_tokens > ctx // 2:
                notes.append(f"{method}'s {name}: its first request on {spec.key} is {tokens:,} tokens of the "
                             f"{ctx:,}-token context; later, longer requests may not fit")
            continue
        size = f"{tokens:,} tokens" if tokens is not None else "too long"
        against = f"the model's {ctx:,}-token context" if ctx else "the model's context"
        source = "as the server said" if refused else n_ctx_source
        raise TooLong(
            f"{label}: {method}'s {name} first request on {spec.key} is {size}, plus {reply_tokens:,} for the "
            f"reply, against {against} ({source}); by part: {_by_part(count, out)}; use a model with a longer "
            f"context" + ("" if not out.images else " or smaller or fewer images (reasoner.options.image_max_px, "
                                                     "reasoner.options.images=measurements)"))
    return notes, set(outgoing)


def _tokens(count: Count, messages: list[dict[str, Any]], options: dict[str, Any]
            ) -> tuple[int | None, int | None, bool]:
    """(prompt tokens, the context the server named, whether it refused the request as too long)."""
    try:
        completion = count(messages, options)
    except ContextTooLong as exc:
        return exc.n_prompt, exc.n_ctx, True
    except Refused:
        return _tokens(count, messages, {}) if options else (None, None, False)
    usage = getattr(completion, "usage", None)
    return getattr(usage, "prompt_tokens", None), None, False


def _by_part(count: Count, out: Any) -> str:
    """Each part's tokens (the endpoint counts each alone, less an empty message's), largest first."""
    base = _tokens(count, [{"role": "user", "content": "."}], {})[0] or 0
    sizes: dict[str, int | None] = {}
    for name, text in out.parts.items():
        try:
            n = _tokens(count, [{"role": "user", "content": text}], {})[0]
        except EndpointError:
            n = None
        sizes[name] = None if n is None else max(0, n - base)
    if out.images:
        content = [{"type": "image_url", "image_url": {"url": url}} for url in out.images]
        try:
            n = _tokens(count, [{"role": "user", "content": [{"type": "text", "text": "."}, *content]}], {})[0]
        except EndpointError:
            n = None
        sizes[f"{len(out.images)} image(s)"] = None if n is None else max(0, n - base)
    ranked = sorted(sizes.items(), key=lambda kv: -(kv[1] if kv[1] is not None else -1))
    text = ", ".join(f"{name} {_n(n)}" if n is not None else f"{name} (not counted)" for name, n in ranked)
    largest = ranked[0][0] if ranked and ranked[0][1] is not None else None
    return text + (f"; the {largest} is the largest" if largest else "")


def _n(tokens: int | None) -> str:
    return "?" if tokens is None else f"{tokens:,}"


__all__ = ["TooLong", "check_first_requests"]
