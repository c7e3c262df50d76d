"""The common interface of the constraint and monitor templates (kintsugi.taskgraph.constraints)."""

from __future__ import annotations

from typing import Iterator

from kintsugi.taskgraph.base import GraphModel
from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.geometry import RefRole


class _Template(GraphModel):
    """Common interface; subclasses set `kind` and implement `evaluate` and `refs`."""

    def evaluate(self, f: Features) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def refs(self) -> Iterator[tuple[str, RefRole, str | None]]:  # pragma: no cover - abstract
        """(entity, role, feature) for every name this template reads, for vocabulary checks."""
        raise NotImplementedError

    def bind(self, f: Features) -> "_Template":
        """Fill references taken at edge start (see `drift`); others are returned unchanged."""
        return self

    @property
    def bound(self) -> bool:
        return True
