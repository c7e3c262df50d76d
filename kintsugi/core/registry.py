"""One registry per kind (tasks, methods): name -> factory, description, tags, config class.

Built-in entries register when their modules are imported (`kintsugi.core.plugins.load_builtins`);
a user's own task or method registers the same way from a plugin module.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Generic, Iterator, TypeVar

from kintsugi.core.config import StrictModel, apply_overrides
from kintsugi.core.errors import ConfigError, UnknownNameError

T = TypeVar("T")


class NoSettings(StrictModel):
    """The config of an entry that has no settings: any `--set` key for it is an error."""


@dataclass(frozen=True)
class Entry(Generic[T]):
    name: str
    factory: T
    description: str
    tags: frozenset[str] = field(default_factory=frozenset)
    config: type[StrictModel] = NoSettings
    """The entry's typed settings; `--set <kind>.<key>=value` is validated against it."""

    def configure(self, overrides: dict[str, Any] | list[str], prefix: str = "method") -> StrictModel:
        """The entry's settings with dotted overrides applied (errors name `<prefix>.<key>`)."""
        try:
            return apply_overrides(self.config(), overrides, prefix=prefix)
        except ConfigError as exc:
            raise ConfigError(f"{exc} (the settings of {prefix} {self.name!r})") from None


class Registry(Generic[T]):
    """A named collection of factories; unknown names raise with the known ones listed."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, Entry[T]] = {}

    def register(self, name: str, description: str, tags: tuple[str, ...] = (),
                 config: type[StrictModel] = NoSettings) -> Callable[[T], T]:
        def decorator(factory: T) -> T:
            if name in self._entries:
                raise ValueError(f"{self.kind} {name!r} registered twice")
            self._entries[name] = Entry(name, factory, description, frozenset(tags), config)
            return factory

        return decorator

    def get(self, name: str) -> Entry[T]:
        try:
            return self._entries[name]
        except KeyError:
            known = ", ".join(sorted(self._entries)) or "(none)"
            raise UnknownNameError(f"unknown {self.kind} {name!r}; known: {known}") from None

    def __contains__(self, name: str) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[Entry[T]]:
        return iter(sorted(self._entries.values(), key=lambda e: e.name))

    def names(self) -> list[str]:
        return sorted(self._entries)


TASKS: Registry[Callable[[], Any]] = Registry("task")
"""Task name -> factory() returning a `kintsugi.core.task.Task`."""
METHODS: Registry[Callable[[Any, Any], Any]] = Registry("method")
"""Method name -> factory(context, settings) returning an object with `run(robot, log) -> bool`."""
REASONERS: Registry[Callable[[Any, Any], Any]] = Registry("reasoner")
"""Reasoner backend name -> factory(ReasonerSettings, options) returning a `kintsugi.reasoning.base.Reasoner`;
the entry's config validates `ReasonerSettings.options`."""
