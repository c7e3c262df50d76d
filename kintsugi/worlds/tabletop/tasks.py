"""The tabletop tasks kintsugi ships: importing this module registers each declared spec."""

from __future__ import annotations

from kintsugi.core.registry import TASKS
from kintsugi.worlds.tabletop.block_in_bin import SPEC as BLOCK_IN_BIN
from kintsugi.worlds.tabletop.coffee_tray import SPEC as COFFEE
from kintsugi.worlds.tabletop.fold_towel import SPEC as FOLD_TOWEL, FoldTowelTask
from kintsugi.worlds.tabletop.flank_box import SPEC as FLANK_BOX
from kintsugi.worlds.tabletop.handover_block import SPEC as HANDOVER
from kintsugi.worlds.tabletop.pour_dual import SPEC as POUR_DUAL
from kintsugi.worlds.tabletop.pour_single import SPEC as POUR_SINGLE
from kintsugi.worlds.tabletop.rearrange_table import SPEC as REARRANGE
from kintsugi.worlds.tabletop.stack_blocks import SPEC as STACK_BLOCKS
from kintsugi.worlds.tabletop.task import register

SPECS = (POUR_SINGLE, POUR_DUAL, REARRANGE, HANDOVER, COFFEE, STACK_BLOCKS, FLANK_BOX, BLOCK_IN_BIN)
for _spec in SPECS:
    register(_spec)
TASKS.register(FOLD_TOWEL.name, FOLD_TOWEL.description, tags=("system-b", "tabletop"))(lambda: FoldTowelTask(FOLD_TOWEL))
