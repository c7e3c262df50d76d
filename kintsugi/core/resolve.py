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
