"""The tabletop tasks kintsugi ships: importing this module registers each declared spec."""

from __future__ import annotations

from kintsugi.tasks.tabletop.pour_single import SPEC as POUR_SINGLE
from kintsugi.tasks.tabletop.task import register

SPECS = (POUR_SINGLE,)
for _spec in SPECS:
    register(_spec)
