"""The peg-insertion task: spec -> world + robot + method -> scored TrialRecord."""

from __future__ import annotations

import time
from typing import Callable

from kintsugi.config import apply_overrides
from kintsugi.errors import KintsugiError
from kintsugi.methods import METHODS
from kintsugi.tasks import TASKS
from kintsugi.tasks.peg.conditions import sample_params
from kintsugi.tasks.peg.config import CONDITIONS, PegTaskConfig
from kintsugi.tasks.peg.context import PegContext
from kintsugi.tasks.peg.robot import PegRobot
from kintsugi.tasks.peg.shapes import SHAPES_HELP, peg_shape
from kintsugi.tasks.peg.suites import SUITES
from kintsugi.tasks.peg.world import PegWorld
from kintsugi.trial import TrialLog, TrialRecord, TrialSpec
from kintsugi.video import VideoRecorder

RECOVERY_SKILLS = ("fit", "align", "insert")


class PegInsertionTask:
    name = "peg-insertion"
    config_type = PegTaskConfig
    variants_help = SHAPES_HELP
    default_variants = ("round", "square", "rectangle")
    conditions = CONDITIONS
    default_conditions = tuple(CONDITIONS)
    method_tag = "peg-insertion"
    """Methods carrying this tag run this task (checked before any trial)."""
    reference_method = "baseline"
    suites = SUITES
    """Named campaigns, `kintsugi bench peg-insertion --suite stretch`."""

    def config(self, overrides: dict | list) -> PegTaskConfig:
        return apply_overrides(PegTaskConfig(), overrides)

    def check_variant(self, name: str, cfg: PegTaskConfig) -> None:
        """Raise ConfigError for an unknown peg shape (campaign validation, before any trial)."""
        peg_shape(name, cfg)

    def run(self, spec: TrialSpec, echo: Callable[[str], None] | None = None) -> TrialRecord:
        import kintsugi.methods.builtin  # noqa: F401 - registers the built-in methods

        start = time.perf_counter()
        cfg = self.config(spec.overrides)
        params = sample_params(cfg, spec.variant, spec.condition, spec.seed)
        method_factory = METHODS.get(spec.method).factory
        ctx = PegContext(cfg=cfg, shape=spec.variant, reasoner=spec.reasoner)  # no seed: it would re-draw the truth
        method = method_factory(ctx)
        recorder = VideoRecorder() if spec.video else None
        world = PegWorld(cfg, params)
        robot = PegRobot(world, spec.variant, on_tick=recorder.on_tick if recorder else None)

        def on_status(label: str, verdict: str | None) -> None:
            if recorder is not None:
                recorder.status(label, verdict)

        log = TrialLog(echo=echo, on_status=on_status)
        error = None
        framework_success = False
        try:
            framework_success = bool(method.run(robot, log))
        except KintsugiError as exc:
            error = f"{type(exc).__name__}: {exc}"
            log.event(robot.sim_time, "error", error)
        truth = world.ground_truth()
        video = None
        if recorder is not None and recorder.frames:
            ok = framework_success and error is None  # scored: the recorder may show the truth now
            recorder.finish(f"outcome: ground truth G {'SUCCESS' if truth.success else 'FAILURE'}, "
                            f"framework F {'success' if ok else 'failure'}", truth.success)
            video = str(recorder.save(spec.video))
        world.close()
        calls = log.transcript
        return TrialRecord(
            key=spec.key, task=spec.task, method=spec.method, variant=spec.variant,
            condition=spec.condition, seed=spec.seed,
            params=params.model_dump() | {"tip_depth_mm": round(truth.tip_depth_mm, 3),
                                          "tip_offset_mm": round(truth.tip_offset_mm, 3),
                                          "tip_offset_x_mm": round(truth.tip_offset_x_mm, 3),
                                          "tilt_deg": round(truth.tilt_deg, 3)},
            success=truth.success, framework_success=framework_success and error is None,
            executions=dict(log.executions),
            extra_executions={s: max(0, log.executions.get(s, 0) - 1) for s in RECOVERY_SKILLS},
            transitions=log.transitions, skills=log.skills, events=log.events,
            sim_time=round(robot.sim_time, 4), wall_time=time.perf_counter() - start,
            physics_steps=world.steps, reasoning_calls=len(calls),
            reasoning_latency_s=sum(c.get("latency_s", 0.0) for c in calls),
            reasoning_errors=sum(1 for c in calls if c.get("error")),
            transcript=calls, error=error, video=video,
        )


@TASKS.register("peg-insertion", "soft-wrist peg-in-hole with contact-formation skills and recovery (system A)",
                tags=("system-a",))
def make_peg_task() -> PegInsertionTask:
    return PegInsertionTask()
