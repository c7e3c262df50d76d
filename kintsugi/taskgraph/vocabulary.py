"""What a task graph may name: atomic actions (with argument checks), objects, arms and features.

The task/world supplies one; this package ships none, so no task knowledge lives here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Union

from pydantic import BaseModel, ValidationError

from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.features import ARM_FEATURES, OBJECT_FEATURES

ArgValidator = Union[Callable[[dict[str, Any]], object], type[BaseModel], None]
"""Checks one action's arguments: a callable that raises on bad args, a pydantic model, or None (any args)."""


def _known(names) -> str:
    return ", ".join(sorted(names)) or "(none)"


def _first_error(exc: ValidationError) -> str:
    errs = exc.errors()
    parts = [f"{'.'.join(str(p) for p in e['loc']) or '(args)'}: {e['msg']}" for e in errs[:3]]
    return "; ".join(parts) + (f" (+{len(errs) - 3} more)" if len(errs) > 3 else "")


@dataclass(frozen=True)
class Vocabulary:
    """Action names -> argument validator, object names, object feature names, arm names."""

    actions: Mapping[str, ArgValidator]
    objects: frozenset[str]
    features: frozenset[str] = OBJECT_FEATURES
    arms: frozenset[str] = frozenset({"left", "right"})

    def __post_init__(self) -> None:
        clash = set(self.objects) & set(self.arms)
        if clash:
            raise GraphError(f"vocabulary names {_known(clash)} both as object and arm; rename one")

    def check_action(self, name: str, args: dict[str, Any], where: str) -> None:
        """Raise GraphError naming `where` if the action is unknown or its arguments are rejected."""
        if name not in self.actions:
            raise GraphError(f"{where}: unknown action {name!r}; known: {_known(self.actions)}")
        validator = self.actions[name]
        if validator is None:
            return
        try:
            if isinstance(validator, type) and issubclass(validator, BaseModel):
                validator.model_validate(args)
            else:
                validator(args)
        except GraphError as exc:
            raise GraphError(f"{where}: action {name!r} arguments rejected: {exc}") from None
        except ValidationError as exc:
            raise GraphError(f"{where}: action {name!r} arguments rejected: {_first_error(exc)}") from None
        except Exception as exc:  # a validator tripping on hostile input is still just bad input
            raise GraphError(f"{where}: action {name!r} arguments rejected: {type(exc).__name__}: {exc}") from None

    def check_ref(self, entity: str, role: str, feature: str | None, where: str) -> None:
        """One (entity, role, feature) reference from a constraint template; see `_Template.refs`."""
        is_arm, is_obj = entity in self.arms, entity in self.objects
        if role == "arm" and not is_arm:
            raise GraphError(f"{where}: unknown arm {entity!r}; arms: {_known(self.arms)}")
        if role == "object" and not is_obj:
            raise GraphError(f"{where}: unknown object {entity!r}; objects: {_known(self.objects)}")
        if role == "point" and not (is_arm or is_obj):
            raise GraphError(
                f"{where}: unknown object or arm {entity!r}; objects: {_known(self.objects)}; arms: {_known(self.arms)}"
            )
        if feature is None and role == "point" and is_obj:
            feature = "centroid"
        if feature is None:
            return
        if is_arm and role != "object":
            allowed = {"eef"} if role == "point" else ARM_FEATURES
            if feature not in allowed:
                raise GraphError(f"{where}: arm {entity!r} has no feature {feature!r}; use one of {_known(allowed)}")
        elif feature not in self.features:
            raise GraphError(f"{where}: unknown feature {feature!r} of {entity!r}; features: {_known(self.features)}")
