"""The tabletop tasks kintsugi ships: importing this module registers each declared spec."""

from __future__ import annotations

from kintsugi.tasks import TASKS
from kintsugi.tasks.tabletop.coffee_tray import SPEC as COFFEE
from kintsugi.tasks.tabletop.fold_towel import SPEC as FOLD_TOWEL, FoldTowelTask
from kintsugi.tasks.tabletop.handover_block import SPEC as HANDOVER
from kintsugi.tasks.tabletop.pour_dual import SPEC as POUR_DUAL
from kintsugi.tasks.tabletop.pour_single import SPEC as POUR_SINGLE
from kintsugi.tasks.tabletop.rearrange_table import SPEC as REARRANGE
from kintsugi.tasks.tabletop.task import register

SPECS = (POUR_SINGLE, POUR_DUAL, REARRANGE, HANDOVER, COFFEE)
for _spec in SPECS:
    register(_spec)
TASKS.register(FOLD_TOWEL.name, FOLD_TOWEL.description, tags=("system-b", "tabletop"))(lambda: FoldTowelTask(FOLD_TOWEL))
