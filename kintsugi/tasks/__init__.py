"""Task registry: each entry's factory returns an object with `run(spec) -> TrialRecord`."""

from kintsugi.registry import Registry

TASKS: Registry = Registry("task")


def load_all() -> None:
    """Import every built-in task module so its registration runs."""
    from kintsugi.tasks.peg import task  # noqa: F401
    from kintsugi.tasks.tabletop import tasks  # noqa: F401
    from kintsugi.tasks.contact import tasks as contact_tasks  # noqa: F401
