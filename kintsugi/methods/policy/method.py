"""The `policy` method: a policy run closed-loop through the step-level API, as a method among methods.

`kintsugi run <task> --method policy --set method.path=<module:callable | file.npz>` runs it on any
task of the three systems, with the task's seeds, conditions and disturbances, and the one runner's
record (scored by the task, never by the policy). Each control step: observe (the robot's sensors, and
cameras unless the policy says `images = False`), ask the policy, send its action, step the world. The
run ends when the policy returns None or after `max_seconds` of sim time. The method's verdict is the
policy's own claim (`verdict`, default False: a policy that claims nothing never passes for a success).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import KintsugiError
from kintsugi.core.log import TrialLog
from kintsugi.core.registry import METHODS
from kintsugi.methods.policy.drivers import driver_for
from kintsugi.methods.policy.policies import load_policy


class PolicySettings(StrictModel):
    path: str = ""
    """`module:attribute` (a policy, or a class built with no arguments) or a .npz file (a trajectory to
    replay, or a fitted linear policy)."""
    max_seconds: float = Field(120.0, gt=0)
    """Sim time after which the run stops, whatever the policy says."""
    period_s: float = Field(2.0, gt=0)
    """Tabletop: a disturbance that strikes during an atomic action is told of one every period_s."""


class PolicyMethod:
    def __init__(self, ctx: Any, settings: PolicySettings) -> None:
        self.settings = settings
        self.policy = load_policy(settings.path)

    def run(self, robot: Any, log: TrialLog) -> bool:
        p = self.policy
        options = dict(getattr(p, "driver_options", {}) or {})
        if "schedule" not in options and type(robot).__name__ == "TabletopRobot":
            options["period_s"] = self.settings.period_s
        driver = driver_for(robot, **options)
        images = bool(getattr(p, "images", True))
        restarts = set(getattr(p, "restarts", ()) or ())
        if hasattr(p, "reset"):
            p.reset()
        limit = max(1, round(self.settings.max_seconds * driver.control_hz))
        t0 = driver.sim_time
        log.event(t0, "policy", f"{self.settings.path} on the {driver.family} driver at {driver.control_hz:g} Hz")
        while driver.steps < limit:
            if driver.steps in restarts:
                driver.restart()
            action = p(driver.observe(images=images))
            if action is None:
                break
            try:
                driver.apply(action)
            except KintsugiError as exc:
                log.event(driver.sim_time, "policy", f"refused action at step {driver.steps}: {exc}")
                return False
            driver.tick()
        ended = "the policy stopped" if driver.steps < limit else f"the time limit ({self.settings.max_seconds:g} s)"
        log.event(driver.sim_time, "policy", f"{driver.steps} control steps, {ended}")
        return bool(getattr(p, "verdict", False))


@METHODS.register("policy", "a policy (module:callable, a replayed trajectory or a fitted .npz) run closed-loop "
                  "through the step-level API at the control rate; its verdict is the policy's own claim",
                  tags=("peg-insertion", "system-b", "system-c", "policy"), config=PolicySettings)
def make(ctx: Any, settings: PolicySettings) -> PolicyMethod:
    return PolicyMethod(ctx, settings)
