"""What a tabletop method is given besides the robot: the config, the task's declaration, the reasoner."""

from __future__ import annotations

from dataclasses import dataclass, field

from kintsugi.tasks.tabletop.config import TabletopConfig
from kintsugi.tasks.tabletop.spec import TaskSpec
from kintsugi.trial import ReasonerSettings


@dataclass
class TabletopContext:
    """Task-level knowledge only (instruction, goal predicates, nominal script): no trial truth."""

    cfg: TabletopConfig
    task: TaskSpec
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)

    @property
    def task_text(self) -> str:
        return self.task.instruction
