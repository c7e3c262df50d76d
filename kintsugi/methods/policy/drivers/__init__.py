"""Step-level drivers over each family's robot (see `base.Driver`); `driver_for` picks one by the robot."""

from __future__ import annotations

from typing import Any

from kintsugi.methods.policy.drivers.base import Driver, DriverError, Feature


def driver_for(robot: Any, **options: Any) -> Driver:
    """The driver of `robot` (a peg, tabletop or contact robot); options go to the tabletop driver."""
    from kintsugi.worlds.contact.robot import ContactRobot
    from kintsugi.worlds.peg.robot import PegRobot
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    if isinstance(robot, TabletopRobot):
        from kintsugi.methods.policy.drivers.tabletop import TabletopDriver

        return TabletopDriver(robot, **options)
    if options:
        raise DriverError(f"driver options {sorted(options)} are for the tabletop robot, not {type(robot).__name__}")
    if isinstance(robot, PegRobot):
        from kintsugi.methods.policy.drivers.peg import PegDriver

        return PegDriver(robot)
    if isinstance(robot, ContactRobot):
        from kintsugi.methods.policy.drivers.contact import ContactDriver

        return ContactDriver(robot)
    raise DriverError(f"no step-level driver for a {type(robot).__name__}; known: PegRobot, TabletopRobot, "
                      "ContactRobot")


__all__ = ["Driver", "DriverError", "Feature", "driver_for"]
