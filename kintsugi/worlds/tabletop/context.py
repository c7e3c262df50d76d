"""What a tabletop method is given besides the robot: the config, the task's declaration, the reasoner."""

from __future__ import annotations

from dataclasses import dataclass, field

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.spec import TaskSpec
from kintsugi.core.record import ReasonerSettings


@dataclass
class TabletopContext:
    """Task-level knowledge only (instruction, goal predicates, nominal script): no trial truth."""

    cfg: TabletopConfig
    task: TaskSpec
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)

    @property
    def task_text(self) -> str:
        return self.task.instruction
