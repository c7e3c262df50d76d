"""CoRAL on the contact tasks: priors -> memory -> formulation -> MPPI attempts with the outer loop.

One trial:
1. physics priors (role `priors`) from the image, labels and known sizes set the planning world;
2. memory (when `coral.memory_path` names a file): the most similar successful episode of the same
   method, if it scores `coral.memory_threshold`, replaces the formulation call (its code is
   checked and probed again: stored code is as untrusted as a fresh reply);
3. formulation (role `formulate`): staged cost code + contact regions, compiled and probed;
4. up to `coral.max_attempts` MPPI attempts (the scene is reset between them); after a failed
   one, system identification fits the target's mass and friction on the robot's own log and
   the adaptation role (role `adapt`) returns corrected beliefs and/or rewritten code;
5. a success is stored in memory (refined beliefs, code, regions, stages).

Variants switch parts off: `l2r` (no contact regions, one attempt, no adaptation, no memory),
`coral-no-memory`, `coral-no-refinement` (attempts repeat with the same beliefs and code),
`coral-no-contact` (no contact regions). The method never sees the trial's truth.
"""

from __future__ import annotations

import json
import math
import time
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from kintsugi.core.errors import KintsugiError, ReasoningError
from kintsugi.core.log import TrialLog
from kintsugi.methods.coral.beliefs import dump, episode_notes, rescale, stressed, transfer
from kintsugi.methods.coral.figures import CoralFigures
from kintsugi.methods.coral.views import object_label, object_views, scene_png


def probe_limits() -> Any:
    """The sandbox's limits, with a longer wall-clock allowance: on a loaded machine a child process can take
    seconds just to start; CPU time and memory stay the sandbox's defaults."""
    from kintsugi.sandbox import ProbeLimits

    return ProbeLimits(wall_s=60.0)


@dataclass(frozen=True)
class Variant:
    name: str
    memory: bool = True
    refine: bool = True
    contact: bool = True
    attempts: int | None = None
    """None: `coral.max_attempts`."""


VARIANTS = {
    "coral": Variant("coral"),
    "l2r": Variant("l2r", memory=False, refine=False, contact=False, attempts=1),
    "coral-no-memory": Variant("coral-no-memory", memory=False),
    "coral-no-refinement": Variant("coral-no-refinement", refine=False),
    "coral-no-contact": Variant("coral-no-contact", contact=False),
}


class Coral:
    def __init__(self, ctx: Any, variant: Variant) -> None:
        self.ctx, self.variant = ctx, variant
        self.attempts: list[dict[str, Any]] = []
        self._guards: tuple = ()
        self.info: dict[str, Any] = {"variant": variant.name}
        self._now = 0.0
        self._seed = 0
        self._png: bytes | None = None
        """The scene camera's image at the start, sent with the priors and formulation requests."""
        self.clock = {"planning": 0.0, "physics": 0.0, "sysid": 0.0, "reasoning": 0.0}
        """Wall seconds by where they went: MPPI iterations, the robot acting (physics, sensors, inner-rate checks),
        system identification, the roles (priors, formulation, adaptation: reply, checks and probes)."""

    # --- building the requests --------------------------------------------------------------------------------
    def scene_request(self, obs: Any, priors: dict[str, Any]) -> Any:
        from kintsugi.methods.coral.types import FixtureView, FormulationRequest, MarkerView, ObjectState, RobotView
        from kintsugi.methods.coral.formulate import variable_docs
        from kintsugi.sandbox import FUNCTIONS
        from kintsugi.worlds.contact.world import tilt_deg, yaw_of

        ctx, cfg, scene = self.ctx, self.ctx.cfg, self.ctx.known
        from kintsugi.methods.coral.nouns import colour_name

        objects = []
        for name, geo in scene.geometry.items():
            o = obs.objects[name]
            objects.append(ObjectState(name=name, label=object_label(scene, name),
                                       size_m=tuple(2 * h for h in geo.parts[0].half),
                                       pos_m=tuple(float(x) for x in o.pos),
                                       yaw_deg=math.degrees(float(yaw_of(o.quat))),
                                       upright_deg=float(tilt_deg(o.quat)), shape=geo.parts[0].shape,
                                       colour=colour_name(geo.rgba), material=geo.material))
        fixtures = [FixtureView(name=k, lo_m=tuple(p - h for p, h in zip(f.pos, f.half)),
                                hi_m=tuple(p + h for p, h in zip(f.pos, f.half)), label=f.label)
                    for k, f in scene.fixtures.items()]
        markers = [MarkerView(name=k, x_m=m.x, y_m=m.y, radius_m=m.radius, label=m.label or f"{colour_name(m.rgba)} disc")
                   for k, m in scene.markers.items()]
        e = cfg.effector
        robot = RobotView(max_opening_m=e.max_opening_m, finger_length_m=e.finger_length_m, kp_n_per_m=e.kp_n_per_m,
                          force_limit_n=e.force_limit_n, table_edge_x_m=cfg.table.edge_x_m, home_m=e.home_m)
        docs = variable_docs(None, list(scene.geometry), list(scene.fixtures), list(scene.markers), self.variant.contact)
        return FormulationRequest(task=ctx.task_text, objects=objects, fixtures=fixtures, markers=markers, robot=robot,
                                  priors=priors, variables=docs, functions=dict(FUNCTIONS),
                                  contact_strategy=self.variant.contact, image_png=self._png)

    # --- the trial ----------------------------------------------------------------------------------------------
    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.reasoning import make_reasoner
        from kintsugi.reasoning.base import RecordingReasoner

        reasoner = RecordingReasoner(make_reasoner(self.ctx.reasoner), records=[])
        t0 = time.perf_counter()
        try:
            return self._run(robot, log, reasoner)
        finally:
            log.transcript.extend(r.model_dump(mode="json") for r in reasoner.records)
            spent = {k: round(v, 3) for k, v in self.clock.items()}
            spent["other"] = round(max(0.0, time.perf_counter() - t0 - sum(self.clock.values())), 3)
            log.figures(CoralFigures(**self.info, attempts=self.attempts, time_breakdown_wall_s=spent))

    @contextmanager
    def _timed(self, where: str) -> Iterator[None]:
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.clock[where] += time.perf_counter() - t0

    def _steps(self) -> tuple[int, int]:
        c = self.ctx.cfg.control
        return c.samples, max(1, round(c.horizon_s / self.ctx.cfg.sim.planning_timestep_s))

    def _run(self, robot: Any, log: TrialLog, reasoner: Any) -> bool:
        from kintsugi.methods.coral.clearance import guards
        from kintsugi.methods.coral.types import PriorsRequest
        from kintsugi.methods.coral.formulate import ask_formulation
        from kintsugi.methods.coral.priors import ask_priors
        from kintsugi.worlds.contact.objects import Physics
        from kintsugi.worlds.contact.world import PlanningWorld

        from kintsugi.methods.mppi.execute import observation_seed

        ctx, cfg = self.ctx, self.ctx.cfg
        obs = robot.observe()
        self._seed = observation_seed(obs)
        views = object_views(ctx.known)
        with self._timed("reasoning"):
            self._png = scene_png(robot, reasoner)
            priors, notes = ask_priors(reasoner, PriorsRequest(task=ctx.task_text, objects=views, image_png=self._png))
        names = {object_label(ctx.known, n): n for n in ctx.known.geometry}
        beliefs, stress = stressed({names[k]: v for k, v in priors.objects.items()}, cfg.coral)
        if stress:
            log.event(obs.t, "priors", stress)
        self.info["priors"] = {k: v.model_dump() for k, v in beliefs.items()}
        if notes:
            log.event(obs.t, "priors", "; ".join(notes))
        req = self.scene_request(obs, beliefs)
        samples, steps = self._steps()
        plan = program = None
        memory = self._memory()
        if memory is not None:
            plan, program, beliefs = self._recall(memory, req, beliefs, samples, steps, log, obs.t)
        if plan is None:
            with self._timed("reasoning"):
                plan, program, notes = ask_formulation(reasoner, req, samples, steps, probe_limits())
            self.info["plan_from"] = "formulation"
            if notes:
                log.event(obs.t, "formulation", "; ".join(notes))
        planning = PlanningWorld(cfg, ctx.known, {k: Physics(mass_kg=v.mass_kg, friction=v.friction)
                                                  for k, v in beliefs.items()})
        self._guards = guards(req, ctx.known, cfg.perception.latency_s + 1.0 / cfg.perception.rate_hz)
        fitter = None
        attempts = self.variant.attempts or cfg.coral.max_attempts
        for attempt in range(attempts):
            if attempt:
                robot.restart()
                log.event(robot.sim_time, "restart", f"attempt {attempt + 1} of {attempts}")
            robot.new_log()
            record: dict[str, Any] = {"attempt": attempt + 1, "beliefs_before": dump(beliefs),
                                      "source": plan.source, "stages": [s.model_dump() for s in plan.stages],
                                      "regions": [r.model_dump() for r in plan.regions], "knobs": dict(plan.knobs)}
            self.attempts.append(record)
            t_attempt = time.perf_counter()
            result, trace, timing, error = self._attempt(robot, log, plan, program, planning, attempt)
            planned = float(np.sum(trace.iteration_s)) if trace else 0.0
            self.clock["planning"] += planned
            self.clock["physics"] += max(0.0, time.perf_counter() - t_attempt - planned)
            record.update(reached=bool(result is not None and result.reached), cost_error=error,
                          broken=result.broken if result is not None else None,
                          code_ms_per_step=round(1000 * timing.seconds / max(1, timing.calls), 3),
                          mppi_ms_per_step=round(1000 * float(np.mean(trace.iteration_s)), 2) if trace and trace.iteration_s else None)
            if result is not None and result.reached:
                self._remember(memory, req, beliefs, plan)
                return True
            if attempt + 1 == attempts:
                break
            exec_log = robot.new_log()
            if not self.variant.refine:
                record["adaptation"] = "none (this method does not refine)"
                continue
            if fitter is None:
                fitter = self._fitter(planning)
            self._now = robot.sim_time
            with self._timed("sysid"):
                sysid = self._sysid(fitter, exec_log, beliefs, planning, log)
            history = self._history(attempt, result, trace, exec_log, error)
            with self._timed("reasoning"):
                beliefs, plan, program = self._adapt(reasoner, req, beliefs, plan, program, history, sysid, planning,
                                                     samples, steps, log, record)
        return False

    def _attempt(self, robot: Any, log: TrialLog, plan: Any, program: Any, planning: Any, attempt: int):  # noqa: ANN202
        from kintsugi.methods.coral.env import first_env
        from kintsugi.methods.coral.stages import CodeTiming, CostCodeError, build_stages
        from kintsugi.methods.mppi.execute import run_attempt

        timing = CodeTiming()
        factories = build_stages(plan, program, self.ctx.known, self.ctx.cfg, self._seed + 1000 * attempt, timing,
                                 first_env(robot.observe()))
        try:
            result, trace = run_attempt(self.ctx.cfg, robot, planning, factories, log,
                                        seed=self._seed + 1000 * attempt,
                                        guards=tuple(g.fresh() for g in self._guards))
        except CostCodeError as exc:
            log.event(robot.sim_time, "cost error", str(exc)[:300])
            return None, None, timing, str(exc)[:300]
        return result, trace, timing, None

    def _fitter(self, planning: Any) -> Any:
        from kintsugi.methods.mppi.identify import BeliefFitter

        s = self.ctx.cfg.sysid
        return BeliefFitter(planning, self.ctx.task.target, s.mass_bounds_kg, s.friction_bounds)

    def _sysid(self, fitter: Any, exec_log: Any, beliefs: dict, planning: Any, log: TrialLog) -> Any:
        """Fit the target's mass and friction on every logged window so far (a tool the adaptation role reads)."""
        from kintsugi.methods.coral.types import SysIdSummary
        from kintsugi.worlds.contact.objects import Physics

        obj = self.ctx.task.target
        added = fitter.add(exec_log)
        if not fitter.logs:
            return None
        current = beliefs[obj]
        planning.set_beliefs({obj: Physics(mass_kg=current.mass_kg, friction=current.friction)})
        try:
            phys, fit = fitter.fit()
        except KintsugiError as exc:
            log.event(self._now, "sysid", f"no fit: {exc}"[:200])
            return None
        log.event(self._now, "sysid", fitter.story(added, phys, fit))
        return SysIdSummary(object=obj, mass_kg=phys.mass_kg, friction=phys.friction, loss_prior=fit.prior_loss,
                            loss_fit=fit.loss, windows=len(fitter.logs), adopted=fitter.kept is None,
                            kept_because=fitter.kept)

    def _history(self, attempt: int, result: Any, trace: Any, exec_log: Any, error: str | None) -> Any:
        from kintsugi.methods.coral.types import AttemptHistory, StageOutcome
        from kintsugi.worlds.contact.world import tilt_deg

        stages, failed = [], None
        for tr in (result.stages if result is not None else []):
            costs = [c for c, s in zip(trace.cost, trace.stage) if s == tr.stage and math.isfinite(c)] if trace else []
            stages.append(StageOutcome(name=tr.stage, reached=tr.reached, seconds=round(tr.t_exit - tr.t_enter, 3),
                                       cost_first=costs[0] if costs else None, cost_last=costs[-1] if costs else None,
                                       cost_min=min(costs) if costs else None))
            if not tr.reached and failed is None:
                failed = tr.stage
        obs = exec_log.obs
        travel, tilt, forces, press = {}, {}, [0.0], None
        if obs:
            for name in obs[0].objects:
                travel[name] = round(float(np.linalg.norm(obs[-1].objects[name].pos - obs[0].objects[name].pos)), 4)
                tilt[name] = round(float(tilt_deg(obs[-1].objects[name].quat)), 2)
            forces = [float(np.linalg.norm(o.force)) for o in obs]
        press_stage = next((s for s in self.attempts[-1]["stages"] if s.get("press_n") is not None), None)
        if press_stage is not None and result is not None:
            tr = next((t for t in result.stages if t.stage == press_stage["name"]), None)
            if tr is not None:
                axis = press_stage["press_axis"]
                vals = [abs(float(o.force[axis])) for o in obs if tr.t_enter <= o.t <= tr.t_exit]
                press = round(float(np.mean(vals)), 3) if vals else None
        held = [min(o.touch) > 0.5 for o in obs]
        lost = any(a and not b for a, b in zip(held, held[1:])) and bool(held) and not held[-1]
        return AttemptHistory(attempt=attempt + 1, stages=stages, failed_stage=failed, max_force_n=round(max(forces), 3),
                              mean_press_force_n=press, object_travel_m=travel, object_tilt_deg=tilt,
                              touch_lost_while_held=lost, cost_error=error,
                              broken=result.broken if result is not None else None)

    def _adapt(self, reasoner: Any, req: Any, beliefs: dict, plan: Any, program: Any, history: Any, sysid: Any,
               planning: Any, samples: int, steps: int, log: TrialLog, record: dict) -> tuple[dict, Any, Any]:
        from kintsugi.methods.coral.adapt import ask_adaptation
        from kintsugi.methods.coral.types import AdaptRequest
        from kintsugi.worlds.contact.objects import Physics

        past = [h for h in (a.get("history") for a in self.attempts) if h]
        record["history"] = history.model_dump()
        record["sysid"] = sysid.model_dump() if sysid else None
        areq = AdaptRequest(task=req.task, scene=req, beliefs=beliefs, source=plan.source, stages=plan.stages,
                            regions=plan.regions, knobs=plan.knobs,
                            history=[*[type(history).model_validate(h) for h in past[:-1]], history][-5:],
                            sysid=sysid, refine_strategy=True)
        try:
            reply, new_plan, new_program, notes = ask_adaptation(reasoner, areq, samples, steps, probe_limits())
        except ReasoningError as exc:
            record["adaptation"] = f"error: {exc}"[:400]
            log.event(self._now, "adapt", f"no usable adaptation ({exc}); next attempt unchanged"[:300])
            planning.set_beliefs({k: Physics(mass_kg=v.mass_kg, friction=v.friction) for k, v in beliefs.items()})
            return beliefs, plan, program
        new_beliefs = reply.beliefs if reply.beliefs is not None else beliefs
        planning.set_beliefs({k: Physics(mass_kg=v.mass_kg, friction=v.friction) for k, v in new_beliefs.items()})
        record.update(adaptation=reply.diagnosis, adaptation_notes=notes, beliefs_after=dump(new_beliefs),
                      code_changed=new_program is not None)
        log.event(self._now, "adapt", reply.diagnosis[:300])
        return new_beliefs, new_plan, new_program or program

    # --- memory -------------------------------------------------------------------------------------------------
    def _memory(self) -> Any:
        path = self.ctx.cfg.coral.memory_path
        if not self.variant.memory or not path:
            return None
        from kintsugi.methods.coral.memory.store import EpisodeMemory

        return EpisodeMemory(path)

    def _recall(self, memory: Any, req: Any, beliefs: dict, samples: int, steps: int, log: TrialLog, t: float
                ) -> tuple[Any, Any, dict]:
        from kintsugi.methods.coral.types import FormulationReply, ObjectView, StageSpec
        from kintsugi.methods.coral.formulate import check_formulation
        from kintsugi.reasoning.jsontext import BadReply

        views = [ObjectView(label=o.name, size_m=o.size_m) for o in req.objects]
        matches = [m for m in memory.search(req.task, views, k=max(1, len(memory)))
                   if episode_notes(m.episode).get("method") == self.variant.name]
        best = matches[0] if matches else None
        self.info["memory"] = {"episodes": len(memory), "best_score": round(best.score, 4) if best else None}
        if best is None or best.score < self.ctx.cfg.coral.memory_threshold:
            return None, None, beliefs
        meta = episode_notes(best.episode)
        try:
            stored = FormulationReply(source=best.episode.cost_source,
                                      stages=[StageSpec.model_validate(s) for s in meta.get("stages", [])],
                                      regions=rescale(best.episode, req), knobs=meta.get("knobs", {}),
                                      reasoning=f"memory episode {best.id} (score {best.score:.2f})")
            plan, program, _ = check_formulation(stored, req, samples, steps, probe_limits())
        except (BadReply, ValueError) as exc:
            log.event(t, "memory", f"episode {best.id} unusable ({exc}); formulating instead"[:300])
            return None, None, beliefs
        recalled = {**beliefs, **{k: transfer(v, beliefs[k], meta.get("priors", {}).get(k))
                                  for k, v in best.episode.beliefs.items() if k in beliefs}}
        self.info.update(plan_from=f"memory episode {best.id}", memory_beliefs=dump(recalled))
        log.event(t, "memory", f"episode {best.id} (score {best.score:.2f}) replaces the formulation; beliefs "
                  + ", ".join(f"{k} {v.mass_kg:.3g} kg / {v.friction:.3g}" for k, v in recalled.items()))
        return plan, program, recalled

    def _remember(self, memory: Any, req: Any, beliefs: dict, plan: Any) -> None:
        if memory is None:
            return
        from kintsugi.methods.coral.adapt import ESCALATION_CAP
        from kintsugi.methods.coral.memory.store import Episode
        from kintsugi.methods.coral.types import ObjectView

        # what succeeded (cost, regions, weights, beliefs), not the escalation path: the stages keep the first
        # attempt's timeouts and the knobs drop the time escalation the failed attempts grew
        first = {st["name"]: st["timeout_s"] for st in self.attempts[0]["stages"]} if self.attempts else {}
        stages = [st.model_copy(update={"timeout_s": min(st.timeout_s, first.get(st.name, st.timeout_s))})
                  for st in plan.stages]
        knobs = {k: v for k, v in plan.knobs.items() if k not in ESCALATION_CAP}
        memory.add(Episode(task=self.ctx.task.name, instruction=req.task,
                           objects=[ObjectView(label=o.name, size_m=o.size_m) for o in req.objects],
                           beliefs=beliefs, cost_source=plan.source, regions=plan.regions,
                           notes=json.dumps({"method": self.variant.name, "priors": self.info.get("priors", {}),
                                             "stages": [st.model_dump() for st in stages], "knobs": knobs})))
        memory.close()
