"""From names and `--set` overrides to the objects of a trial, checked before anything runs.

The runner and campaign validation both resolve through here, so a name or a setting is judged the
same way (and worded the same way) whether one trial or a campaign of thousands asks for it.
Overrides split three ways: `reasoner.<key>` go to the reasoner settings, `method.<key>` to every
method's settings, `methods.<name>.<key>` to the method `<name>` only, every other key to the task's.
"""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.registry import METHODS, REASONERS, TASKS, Entry


def split_overrides(overrides: dict[str, Any], method: str | None = None
                    ) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(task, method, reasoner) overrides; the method's are `method.<key>` plus, when `method` is named,
    its own `methods.<method>.<key>` (which win)."""
    mine = f"methods.{method}." if method else None
    common = {k.split(".", 1)[1]: v for k, v in overrides.items() if k.startswith("method.")}
    own = {k.removeprefix(mine): v for k, v in overrides.items() if mine and k.startswith(mine)}
    reasoner = {k.split(".", 1)[1]: v for k, v in overrides.items() if k.startswith("reasoner.")}
    task = {k: v for k, v in overrides.items() if not k.startswith(("method.", "methods.", "reasoner."))}
    return task, common | own, reasoner


def method_for(task: Any, name: str) -> Entry:
    """The method entry `name`, refused unless it drives the task's robot (its tag)."""
    entry = METHODS.get(name)
    if task.method_tag not in entry.tags:
        fits = [e.name for e in METHODS if task.method_tag in e.tags]
        raise ConfigError(f"method {name!r} does not run task {task.name!r} (it drives another robot); "
                          f"methods that do: {', '.join(fits) or '(none)'}")
    return entry


def check_scoped(overrides: dict[str, Any], methods: list[str]) -> None:
    """`methods.<name>.<key>` must name a registered method (a suite may set one the run leaves out)."""
    for key in overrides:
        if key.startswith("methods."):
            name = key.split(".")[1] if key.count(".") >= 2 else ""
            if name not in METHODS:
                raise ConfigError(f"override {key!r} names method {name!r}, which is not registered; "
                                  f"this run's methods: {', '.join(methods)} (write methods.<method>.<key>)")


def resolve(spec: TrialSpec) -> tuple[Any, Any, Any, Any, Any]:
    """(task, method entry, task config, method config, reasoner settings) for a spec; ConfigError names
    what is wrong."""
    load_builtins()
    task = TASKS.get(spec.task).factory()
    entry = method_for(task, spec.method)
    check_scoped(spec.overrides, [spec.method])
    task_overrides, method_overrides, reasoner_overrides = split_overrides(spec.overrides, spec.method)
    cfg = task.config(task_overrides)
    task.check_variant(spec.variant, cfg)
    return task, entry, cfg, entry.configure(method_overrides), reasoner_settings(spec.reasoner, reasoner_overrides)


def backend_options(entry: Any, options: dict[str, Any]) -> Any:
    """A reasoner backend's `options` validated by its settings class; ConfigError names
    `reasoner.options.<key>`."""
    try:
        return entry.config.model_validate(dict(options))
    except ValidationError as exc:
        known = ", ".join(entry.config.model_fields) or "none"
        problems = []
        for err in exc.errors(include_url=False, include_input=False):
            key = ".".join(["reasoner.options", *(str(p) for p in err["loc"])])
            if err["type"] == "extra_forbidden":
                problems.append(f"unknown key {key!r} (the {entry.name} backend's options: {known})")
            else:
                problems.append(f"{key}: {err['msg']}")
        raise ConfigError(f"bad reasoner option: {'; '.join(problems)}") from None


def reasoner_settings(settings: ReasonerSettings, overrides: dict[str, Any]) -> ReasonerSettings:
    """`settings` with `reasoner.*` overrides applied (keys without the prefix: `model`, `options.replies`),
    checked: the backend must be registered and its options pass its settings class. Errors are one
    line naming the key."""
    options = dict(settings.options)
    common: dict[str, Any] = {}
    for key, value in overrides.items():
        if key == "options":
            if not isinstance(value, dict):
                raise ConfigError(f"reasoner.options must be a JSON object of the backend's options, not {value!r}")
            options |= value
        elif key.startswith("options."):
            options[key.removeprefix("options.")] = value
        else:
            common[key] = value
    out = apply_overrides(settings, common, prefix="reasoner") if common else settings
    out = out.model_copy(update={"options": options})
    load_builtins()
    backend_options(REASONERS.get(out.backend), options)
    return out


SETTINGS_SECTIONS = ("task", "method", "methods", "reasoner")
"""Top-level keys of a settings file: the task's config, every method's (`method`), one method's
(`methods.<name>`), the reasoner's."""


def settings_document(task_name: str, method: str | None, overrides: dict[str, Any]) -> dict[str, Any]:
    """The full settings of a task (and of `method`, scoped as `methods.<method>`) with `overrides` applied:
    the layout `kintsugi config` prints and `--config` reads back."""
    load_builtins()
    task = TASKS.get(task_name).factory()
    task_overrides, method_overrides, _ = split_overrides(overrides, method)
    doc: dict[str, Any] = {"task": task.config(task_overrides).model_dump(mode="json")}
    if method:
        check_scoped(overrides, [method])
        doc["methods"] = {method: method_for(task, method).configure(method_overrides).model_dump(mode="json")}
    return doc


def flatten_settings(doc: Any, source: str = "settings") -> dict[str, Any]:
    """A settings document (`task:`, `method:`, `methods:`, `reasoner:` sections) as dotted `--set` keys.

    `task.peg.clearance_mm: 1` becomes `peg.clearance_mm`; the other sections keep their prefix. Nested
    mappings become dotted keys down to their leaves; an empty mapping sets nothing."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{source} must be a mapping with sections {', '.join(SETTINGS_SECTIONS)}; "
                          f"got {type(doc).__name__}")
    out: dict[str, Any] = {}

    def walk(prefix: str, node: Any) -> None:
        if isinstance(node, dict):
            for k, v in node.items():
                walk(f"{prefix}.{k}" if prefix else str(k), v)
        elif prefix:
            out[prefix] = node

    for section, body in doc.items():
        if section not in SETTINGS_SECTIONS:
            raise ConfigError(f"{source}: unknown section {section!r}; sections: {', '.join(SETTINGS_SECTIONS)}")
        if not isinstance(body, dict):
            raise ConfigError(f"{source}: section {section!r} must be a mapping of settings")
        walk("" if section == "task" else section, body)
    return out


def load_settings_file(path: Any) -> dict[str, Any]:
    """A YAML or JSON settings file as dotted overrides (see `flatten_settings`); ConfigError names the problem."""
    from pathlib import Path

    import yaml

    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read the settings file {path}: {exc.strerror or exc}") from None
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise ConfigError(f"the settings file {path} is not valid YAML{where}: "
                          f"{getattr(exc, 'problem', None) or exc}") from None
    return flatten_settings(doc or {}, source=str(path))
