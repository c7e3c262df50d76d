"""Before the first trial: what a model endpoint can do, against what the roles of a campaign's methods need.

`preflight(specs)` groups the trials by reasoner settings, builds each backend once and, when it can
probe (the openai backend's `preflight`), asks the endpoint a few tiny questions: does it take images,
does it honour strict `response_format` json_schema and `tool_choice="required"`, how long is its
context (llama.cpp's `/props`, vLLM's `/v1/models`, or `reasoner.options.context_tokens`; else learnt
from a refusal), and how many tokens each role's fixed prompt costs (the server counts them). It stops
with one line (`CapabilityError`) naming what the endpoint cannot do and which method's roles need it;
otherwise it returns notes (what was learnt, what will fall back to text mode).

A method asks the roles registered by its own package (`Role.package`).
"""

from __future__ import annotations

import base64
import importlib
import pkgutil
import json
import typing
import urllib.error
import urllib.request
from dataclasses import dataclass
from typing import Any, Iterable, Iterator, Literal

from pydantic import BaseModel

from kintsugi.core.errors import ConfigError
from kintsugi.reasoning.endpoint_options import Learnt
from kintsugi.reasoning.images import image_tokens
from kintsugi.reasoning.request_size import TooLong, check_first_requests
from kintsugi.reasoning.roles import ROLES, Role
from kintsugi.reasoning.structured import format_instructions
from kintsugi.reasoning.transport import ContextTooLong, EndpointError, ImagesRefused, Refused, send

REPLY_ALLOWANCE = 256
"""Reply tokens counted into a request's need when reasoner.options.max_reply_tokens is unset."""
PROBE_PNG = base64.b64decode(  # 8x8 grey PNG
    "iVBORw0KGgoAAAANSUhEUgAAAAgAAAAIAQAAAAA2m5eJAAAAC0lEQVR4nGNgQAcAABAAAd8NXmcAAAAASUVORK5CYII=")
ImageUse = Literal["always", "optional", "none"]


class CapabilityError(ConfigError):
    """The endpoint cannot serve the roles a campaign needs (one line: what it lacks, who needs it)."""


@dataclass
class Capabilities:
    where: str
    images: str | None = None
    """Why images cannot be used (None: they can)."""
    json_schema: str | None = None
    tools: str | None = None
    n_ctx: int | None = None
    n_ctx_source: str = ""


def roles_of(method_entry: Any) -> list[Role]:
    """The roles a method may ask: those registered by the package its factory lives in (its modules are
    imported first, since a method may import the modules that register its roles only when it runs)."""
    module = getattr(method_entry.factory, "__module__", "") or ""
    mod = importlib.import_module(module) if module else None
    package = module if hasattr(mod, "__path__") else module.rpartition(".")[0]
    pkg = importlib.import_module(package) if package else None
    if package.startswith("kintsugi.methods.") and hasattr(pkg, "__path__"):
        for info in pkgutil.iter_modules(pkg.__path__):
            importlib.import_module(f"{package}.{info.name}")
    return [r for r in ROLES if module == r.package or module.startswith(r.package + ".")]


def image_use(role: Role) -> ImageUse:
    """'always' when the request type requires an image, 'optional' when it may carry one, else 'none'."""
    if role.sends_images is False:
        return "none"
    found = list(_image_fields(role.request, True, set()))
    if any(found):
        return "always"
    return "optional" if found else "none"


def _image_fields(tp: Any, required: bool, seen: set[Any]) -> Iterator[bool]:
    """One bool per bytes field reachable from `tp`: whether every request must carry it."""
    if tp is bytes:
        yield required
    elif isinstance(tp, type) and issubclass(tp, BaseModel):
        if tp in seen:
            return
        seen.add(tp)
        for field in tp.model_fields.values():
            yield from _image_fields(field.annotation, required and field.is_required(), seen)
    else:
        args = typing.get_args(tp)
        container = typing.get_origin(tp) in (dict, list, tuple, set) or type(None) in args
        for arg in args:
            if arg is not type(None):
                yield from _image_fields(arg, required and not container, seen)


@dataclass
class Findings:
    """A preflight's result for one endpoint: notes for the user, and what the trials are told (`Learnt`)."""

    notes: list[str]
    learnt: Learnt


def preflight(specs: Iterable[Any]) -> list[str]:
    """Check every distinct endpoint of these trial specs once; CapabilityError stops the campaign."""
    return prepare(list(specs))[0]


def prepare(specs: list[Any]) -> tuple[list[str], list[Any]]:
    """(notes, the specs with what the preflight learnt in their reasoner options): the campaign's process
    checks each endpoint once, and its worker processes start from the findings."""
    from kintsugi.core.resolve import resolve
    from kintsugi.reasoning import make_reasoner

    groups: dict[str, tuple[Any, dict[str, list[Role]], dict[str, Any]]] = {}
    keys: dict[str, str | None] = {}
    of_spec: list[str | None] = []
    for spec in specs:
        kind = json.dumps([spec.task, spec.method, spec.overrides, spec.reasoner.model_dump()], default=str)
        if kind not in keys:
            keys[kind] = None
            if spec.reasoner.backend != "embedded" or spec.overrides:
                _, entry, _, _, settings = resolve(spec)
                if settings.backend != "embedded":
                    keys[kind] = settings.model_dump_json()
                    group = groups.setdefault(keys[kind], (settings, {}, {}))
                    group[1][entry.name] = roles_of(entry)
                    group[2].setdefault(entry.name, spec)
        of_spec.append(keys[kind])
    notes: list[str] = []
    learnt: dict[str, Learnt] = {}
    for key, (settings, methods, trials) in groups.items():
        if not any(methods.values()):
            continue
        reasoner = make_reasoner(settings)
        check = getattr(reasoner, "preflight", None)
        if check is None or not getattr(getattr(reasoner, "options", None), "preflight", True):
            continue
        found = check({m: r for m, r in methods.items() if r}, trials)
        if isinstance(found, Findings):
            notes += found.notes
            learnt[key] = found.learnt
        else:  # a backend's own preflight may return notes only
            notes += list(found or [])
    out = []
    for spec, key in zip(specs, of_spec):
        if key in learnt:
            options = {**spec.reasoner.options, "learnt": learnt[key].model_dump()}
            spec = spec.model_copy(update={"reasoner": spec.reasoner.model_copy(update={"options": options})})
        out.append(spec)
    return notes, out


def check_endpoint(reasoner: Any, roles: dict[str, list[Role]], trials: dict[str, Any] | None = None) -> Findings:
    """The openai backend's preflight: probe once, compare with each method's roles, count each role's first
    request on the method's first trial (`trials`; without one, its fixed prompts) (see module doc)."""
    caps = probe(reasoner)
    send_images = reasoner.options.images == "send"
    label = f"{caps.where} (model {reasoner.model})"
    notes: list[str] = []
    text_mode: dict[str, str] = {}
    if caps.images is not None:
        needing = {m: [r.name for r in rs if image_use(r) != "none"] for m, rs in roles.items()}
        needing = {m: names for m, names in needing.items() if names}
        if send_images and needing:
            raise CapabilityError(
                f"{label} takes no images ({caps.images}); {_who(needing)} send camera images: use a vision "
                f"model, or --set reasoner.options.images=measurements to send the checks and measurements instead")
    mode = reasoner.structured.structured_output
    for option, refusal in (("json_schema", caps.json_schema), ("tools", caps.tools)):
        if refusal is None or mode == "text":
            continue
        needing = {m: [r.name for r in rs if (r.tools is not None) == (option == "tools")] for m, rs in roles.items()}
        needing = {m: names for m, names in needing.items() if names}
        if not needing:
            continue
        what = "strict response_format json_schema" if option == "json_schema" else 'tool_choice="required"'
        if mode == "strict":
            raise CapabilityError(f"{label} does not honour {what} ({refusal}); {_who(needing)} need it with "
                                  f"--structured-output strict: use --structured-output auto or text")
        text_mode[option] = f"{what}: {refusal}"
        notes.append(f"{label} does not honour {what} ({refusal}); {_who(needing)} will ask for JSON in text")
    images = "sent" if send_images else "measurements instead (reasoner.options.images)" + (
        f"; {caps.images}" if caps.images else "")
    learnt = Learnt(text_mode=text_mode, context_tokens=caps.n_ctx, images=images)
    counted: dict[str, set[str]] = {}
    reply_tokens = reasoner.options.max_reply_tokens or REPLY_ALLOWANCE
    for method, spec in (trials or {}).items():
        if not roles.get(method):
            continue
        options = {**spec.reasoner.options, "learnt": learnt.model_dump()}
        dry = spec.model_copy(update={"reasoner": spec.reasoner.model_copy(update={"options": options})})
        try:
            found, counted[method] = check_first_requests(
                lambda m, o: _ask(reasoner, m, o), dry, method, [r.name for r in roles[method]], caps.n_ctx,
                caps.n_ctx_source, reply_tokens, label)
        except TooLong as exc:
            raise CapabilityError(str(exc)) from None
        except EndpointError as exc:
            raise CapabilityError(f"preflight of {method}'s first requests at {label}: {exc}") from None
        notes += found
    rest = {m: [r for r in rs if r.name not in counted.get(m, set())] for m, rs in roles.items()}
    notes += _check_context(reasoner, caps, rest, label, send_images)
    return Findings(notes, learnt)


def _who(needing: dict[str, list[str]]) -> str:
    return "; ".join(f"{m}'s {', '.join(names)}" for m, names in needing.items())


def probe(reasoner: Any) -> Capabilities:
    """What the endpoint says about itself, and its answers to three tiny requests."""
    caps = Capabilities(where=reasoner.structured.where)
    props = _get_json(reasoner, "props")
    models = _get_json(reasoner, "models")
    if reasoner.options.context_tokens:
        caps.n_ctx, caps.n_ctx_source = reasoner.options.context_tokens, "reasoner.options.context_tokens"
    elif isinstance(props, dict) and isinstance(props.get("default_generation_settings", {}).get("n_ctx"), int):
        caps.n_ctx, caps.n_ctx_source = props["default_generation_settings"]["n_ctx"], "/props"
    elif isinstance(models, dict):
        for m in models.get("data") or []:
            if isinstance(m, dict) and isinstance(m.get("max_model_len"), int):
                caps.n_ctx, caps.n_ctx_source = m["max_model_len"], "/v1/models"
    vision = (props or {}).get("modalities", {}).get("vision") if isinstance(props, dict) else None
    if vision is False:
        caps.images = "its /props reports no vision modality"
    else:
        caps.images = _probe_images(reasoner)
    caps.json_schema = _probe_option(reasoner, {"response_format": {"type": "json_schema", "json_schema": {
        "name": "Probe", "strict": True, "schema": {"type": "object", "properties": {"ok": {"type": "boolean"}},
                                                    "required": ["ok"], "additionalProperties": False}}}}, None)
    tool = {"type": "function", "function": {"name": "probe", "description": "say ok", "parameters": {
        "type": "object", "properties": {"ok": {"type": "boolean"}}, "required": ["ok"]}}}
    caps.tools = _probe_option(reasoner, {"tools": [tool], "tool_choice": "required"}, "tools")
    return caps


def _base(reasoner: Any) -> str:
    return str(reasoner.client.base_url).rstrip("/")


def _get_json(reasoner: Any, path: str) -> Any:
    base = _base(reasoner)
    url = f"{base.removesuffix('/v1')}/props" if path == "props" else f"{base}/{path}"
    request = urllib.request.Request(url, headers={"Authorization": f"Bearer {reasoner.client.api_key}"})
    try:
        with urllib.request.urlopen(request, timeout=min(10.0, reasoner.timeout_s)) as r:  # noqa: S310 - the user's URL
            return json.loads(r.read())
    except (OSError, ValueError, urllib.error.URLError):
        return None


def _ask(reasoner: Any, messages: list[dict[str, Any]], options: dict[str, Any], max_tokens: int = 1) -> Any:
    def ask(limit: dict[str, int]) -> Any:
        return send(reasoner.client, reasoner.model, messages, {**options, **limit}, where=reasoner.structured.where,
                    timeout_s=reasoner.timeout_s, max_retries=1, what="the preflight")

    try:
        return ask({"max_tokens": max_tokens})
    except EndpointError as exc:
        if "max_completion_tokens" not in str(exc):
            raise
        return ask({"max_completion_tokens": max_tokens})  # OpenAI's reasoning models take only this one


def _probe_images(reasoner: Any) -> str | None:
    text = "Say OK."
    try:
        plain = _ask(reasoner, [{"role": "user", "content": text}], {})
    except EndpointError as exc:
        raise CapabilityError(f"preflight: {exc}") from None
    try:
        with_image = _ask(reasoner, [{"role": "user", "content": [
            {"type": "text", "text": text},
            {"type": "image_url", "image_url": {"url": "data:image/png;base64," + base64.b64encode(PROBE_PNG).decode()}},
        ]}], {})
    except ImagesRefused as exc:
        return str(exc).split(";")[0].split(": ", 1)[-1]
    except EndpointError as exc:  # e.g. llama-cpp-python's formatter failing on list-form content (HTTP 500)
        return f"a request with an image failed where the same text alone did not ({str(exc).split(': ', 1)[-1]})"
    a, b = _prompt_tokens(plain), _prompt_tokens(with_image)
    if a and b is not None and b <= a:
        return (f"it counted {b} prompt tokens with an image against {a} without: the image (and list-form "
                f"content) is dropped")
    return None


def _probe_option(reasoner: Any, options: dict[str, Any], expect: str | None) -> str | None:
    try:
        reply = _ask(reasoner, [{"role": "user", "content": "Answer ok."}], options, max_tokens=48)
    except Refused as refused:
        return f"refused, {refused.reason}"
    except EndpointError as exc:
        return f"error, {exc}"
    if expect == "tools" and reply.choices and not getattr(reply.choices[0].message, "tool_calls", None):
        return "ignored: the reply had no tool call"
    return None


def _prompt_tokens(completion: Any) -> int | None:
    usage = getattr(completion, "usage", None)
    return getattr(usage, "prompt_tokens", None) if usage is not None else None


def _check_context(reasoner: Any, caps: Capabilities, roles: dict[str, list[Role]], label: str,
                   send_images: bool) -> list[str]:
    reply_tokens = reasoner.options.max_reply_tokens or REPLY_ALLOWANCE
    limit_px = reasoner.options.image_max_px
    notes = []
    for method, rs in roles.items():
        for role in rs:
            messages = [{"role": "system", "content": role.system_text()},
                        {"role": "user", "content": f"{role.prompt_text()}\n\n{format_instructions(role.reply)}"}]
            try:
                fixed = _prompt_tokens(_ask(reasoner, messages, {}))
            except ContextTooLong as exc:
                n_ctx = exc.n_ctx or caps.n_ctx
                raise CapabilityError(
                    f"{label}: {method}'s {role.name} prompt alone (system prompt, role prompt and answer format, "
                    f"before any request data) does not fit" + (f" the model's {n_ctx:,}-token context" if n_ctx else
                    " its context") + "; use a model with a longer context") from None
            except (EndpointError, Refused) as exc:
                raise CapabilityError(f"preflight of {method}'s {role.name} at {label}: {exc}") from None
            if fixed is None:
                continue
            images = 0
            if send_images and image_use(role) == "always":
                px = min(role.image_max_px, limit_px or role.image_max_px)
                images = _required_images(role.request) * image_tokens(px, px * 3 // 4)
            need = fixed + images + reply_tokens
            if caps.n_ctx is not None and need > caps.n_ctx:
                raise CapabilityError(
                    f"{label}: {method}'s {role.name} needs at least {need:,} tokens before its request data "
                    f"(prompts {fixed:,}, images {images:,}, reply {reply_tokens:,}) but the model's context is "
                    f"{caps.n_ctx:,} ({caps.n_ctx_source}); use a model with a longer context")
            if caps.n_ctx is not None and need > caps.n_ctx // 2:
                notes.append(f"{method}'s {role.name}: its prompts take {need:,} of the {caps.n_ctx:,}-token context; "
                             f"long requests may not fit")
    if caps.n_ctx is None:
        notes.append(f"{label} does not report its context length; set reasoner.options.context_tokens to "
                     f"have requests checked before they are sent")
    return notes


def _required_images(model: type[BaseModel]) -> int:
    return max(1, sum(_image_fields(model, True, set())))


__all__ = ["CapabilityError", "Capabilities", "Findings", "check_endpoint", "image_use", "prepare", "preflight", "probe",
           "roles_of"]
