"""Hand-written expert costs per contact task: a single-stage cost and a staged FSM.

Each entry maps a task name to (single, fsm): functions of a `ContactContext` returning
the stage factories the planner runs. Both read only what any method may read.
"""

from __future__ import annotations

from typing import Callable

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.expert.designs import boards, flipping, picking, placing, pushing
from kintsugi.methods.mppi.fsm import StageFactory

Design = Callable[[ContactContext], list[StageFactory]]

EXPERTS: dict[str, tuple[Design, Design]] = {
    "push-pick-board": (boards.push_pick_board_single, boards.push_pick_board_fsm),
    "pick-box": (picking.pick_box_single, picking.pick_box_fsm),
    "push-force": (pushing.push_force_single, pushing.push_force_fsm),
    "pick-clutter": (placing.pick_clutter_single, placing.pick_clutter_fsm),
    "flip-box": (flipping.flip_box_single, flipping.flip_box_fsm),
    "flip-wall": (flipping.flip_wall_single, flipping.flip_wall_fsm),
}


def expert_design(task: str, staged: bool) -> Design:
    if task not in EXPERTS:
        raise ConfigError(f"no expert cost for task {task!r}; experts exist for: {', '.join(EXPERTS)}")
    return EXPERTS[task][1 if staged else 0]
