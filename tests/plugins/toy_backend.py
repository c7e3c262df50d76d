"""A toy reasoner backend in one file: every role answered by its embedded solver, each call counted.

Loaded with `--plugin tests.plugins.toy_backend` and chosen with `--reasoner toy`; its calls land in the
transcript under the backend name `toy`.
"""

from __future__ import annotations

from collections import Counter
from typing import Any

from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.embedded import EmbeddedReasoner

CALLS: Counter[str] = Counter()
"""Role name -> calls answered, over the process."""


class CountingReasoner(EmbeddedReasoner):
    name = "toy"

    def answer(self, role: Any, request: Any, check: Any = None) -> Any:
        CALLS[role.name] += 1
        return super().answer(role, request, check)


REASONERS.register("toy", "embedded answers, counted (a test plugin)")(lambda settings, options: CountingReasoner())
