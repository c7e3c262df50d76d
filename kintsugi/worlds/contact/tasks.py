"""Registers system C's contact tasks (importing this module is enough)."""

from kintsugi.worlds.contact import (flip_box, flip_wall, pick_box, pick_clutter, push_around, push_force,
                                     push_pick_board, roll_cylinder, slide_puck)
from kintsugi.worlds.contact.task import register

for _task in (flip_box.TASK, flip_wall.TASK, pick_box.TASK, pick_clutter.TASK, push_force.TASK,
              push_pick_board.TASK, slide_puck.TASK, roll_cylinder.TASK, push_around.TASK):
    register(_task)
