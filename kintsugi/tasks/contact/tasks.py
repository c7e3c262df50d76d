"""Registers system C's contact tasks (importing this module is enough)."""

from kintsugi.tasks.contact import flip_box, flip_wall, pick_box, pick_clutter, push_force
from kintsugi.tasks.contact.task import register

for _task in (flip_box.TASK, flip_wall.TASK, pick_box.TASK, pick_clutter.TASK, push_force.TASK):
    register(_task)
