"""Registers system C's contact tasks (importing this module is enough)."""

from kintsugi.tasks.contact import pick_box
from kintsugi.tasks.contact.task import register

for _task in (pick_box.TASK,):
    register(_task)
