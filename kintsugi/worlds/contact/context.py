"""What a contact method is given besides the robot.

Task knowledge only: the config, the instruction, the objects' known shapes (their 3D
models) and fixtures, and the catalogue (nominal) masses and frictions a prior may start
from. The trial's true physics is reachable only through `oracle_physics`, which the task
fills in for methods registered with the `oracle-physics` tag: the expert baselines, whose
planning world equals the truth BY DESIGN (the paper's upper bound). Everyone else gets None.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.objects import Physics
from kintsugi.worlds.contact.spec import ContactTaskDef
from kintsugi.worlds.contact.world import Scene
from kintsugi.core.record import ReasonerSettings

ORACLE_TAG = "oracle-physics"
METHOD_TAG = "system-c"


@dataclass
class ContactContext:
    cfg: ContactConfig
    task: ContactTaskDef
    known: Scene
    """Object shapes, fixtures and markers (known models); its start poses are the tracker's first reading."""
    nominal: dict[str, Physics]
    """Catalogue masses and frictions (the middle of the config's ranges), never the trial's draws."""
    oracle_physics: dict[str, Physics] | None = None
    """The TRUE masses and frictions: only for `oracle-physics` methods (expert, expert-fsm)."""
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)
    seed: int = 0
    """The trial's seed: seeds the planner's noise, so a trial replays exactly."""

    @property
    def task_text(self) -> str:
        return self.task.instruction
