"""CoRAL's memory in the method: a success is stored (refined beliefs, code, stages, regions) and a later,
similar trial of the same method recalls it instead of formulating, with its regions scaled to the new box;
other methods (ablations) never recall it, and stored code is checked and probed again like a fresh reply."""

from __future__ import annotations

import json

import pytest

from kintsugi.methods.coral.types import ObjectPrior
from kintsugi.methods.coral.costlib import compose
from kintsugi.core.log import TrialLog


def _coral(tmp_path, variant: str, seed: int):  # noqa: ANN001, ANN202
    import kintsugi.worlds.contact.tasks  # noqa: F401
    from kintsugi.methods.coral.method import VARIANTS, Coral
    from kintsugi.core.registry import TASKS
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.worlds.contact.robot import ContactRobot

    task = TASKS.get("push-force").factory()
    cfg = task.config({"coral.memory_path": str(tmp_path / "mem.sqlite")})
    world, _, setup = task.build(cfg, "all", seed)
    ctx = task.context(cfg, setup, False, ReasonerSettings(), seed)
    method = Coral(ctx, VARIANTS[variant])
    req = method.scene_request(ContactRobot(world).observe(), {"box": ObjectPrior(mass_kg=0.04, friction=0.5)})
    world.close()
    return method, req


@pytest.mark.slow
def test_a_success_is_recalled_by_the_same_method_only(tmp_path) -> None:  # noqa: ANN001
    first, req1 = _coral(tmp_path, "coral", 0)
    plan = compose(req1)
    refined = {"box": ObjectPrior(mass_kg=0.55, friction=0.41)}
    first._remember(first._memory(), req1, refined, plan)
    second, req2 = _coral(tmp_path, "coral", 1)
    log = TrialLog()
    recalled, program, beliefs = second._recall(second._memory(), req2, req2.priors, 16, 5, log, 0.0)
    assert recalled is not None and program.has("press_cost") and beliefs["box"].mass_kg == 0.55
    assert second.info["plan_from"].startswith("memory episode")
    scale = req2.objects[0].size_m[0] / req1.objects[0].size_m[0]
    assert recalled.regions[0].center[0] == pytest.approx(plan.regions[0].center[0] * scale)
    other, req3 = _coral(tmp_path, "coral-no-contact", 1)
    assert other._memory() is not None
    assert other._recall(other._memory(), req3, req3.priors, 16, 5, TrialLog(), 0.0)[0] is None
    assert _coral(tmp_path, "coral-no-memory", 1)[0]._memory() is None


def test_stored_code_is_untrusted(tmp_path) -> None:  # noqa: ANN001
    from kintsugi.methods.coral.memory.store import Episode, EpisodeMemory
    from kintsugi.methods.coral.types import ObjectView

    first, req = _coral(tmp_path, "coral", 0)
    plan = compose(req)
    with EpisodeMemory(tmp_path / "mem.sqlite") as mem:
        mem.add(Episode(task="push-force", instruction=req.task,
                        objects=[ObjectView(label=o.name, size_m=o.size_m) for o in req.objects],
                        beliefs={"box": ObjectPrior(mass_kg=0.5, friction=0.4)},
                        cost_source="import os\n" + plan.source, regions=plan.regions,
                        notes=json.dumps({"method": "coral", "stages": [s.model_dump() for s in plan.stages]})))
    log = TrialLog()
    recalled, _, beliefs = first._recall(first._memory(), req, req.priors, 16, 5, log, 0.0)
    assert recalled is None and beliefs == req.priors
    assert any("unusable" in e.detail and "refused" in e.detail for e in log.events)


def test_the_prior_stress_scales_what_the_model_answered_and_says_so() -> None:
    from kintsugi.methods.coral.method import stressed
    from kintsugi.worlds.contact.config import CoralSection

    priors = {"box": ObjectPrior(mass_kg=0.1, friction=0.4)}
    assert stressed(priors, CoralSection()) == (priors, None)
    scaled, note = stressed(priors, CoralSection(prior_mass_scale=8.0, prior_friction_scale=1.8))
    assert scaled["box"].mass_kg == pytest.approx(0.8) and scaled["box"].friction == pytest.approx(0.72)
    assert "x8" in note and "x1.8" in note
    with pytest.raises(ValueError):
        CoralSection(prior_mass_scale=0.0)


def test_a_recalled_mass_is_the_refinement_of_its_prior_not_another_boxs_mass(tmp_path) -> None:  # noqa: ANN001
    """Friction is the material's and carries over; mass carries over as a correction of the episode's own prior
    (the prior scales with the box's size), so a bigger box is not planned with a smaller one's mass."""
    first, req1 = _coral(tmp_path, "coral", 0)
    first.info["priors"] = {"box": {"mass_kg": 0.20, "friction": 0.5, "material": "wood"}}
    first._remember(first._memory(), req1, {"box": ObjectPrior(mass_kg=0.30, friction=0.41)}, compose(req1))
    second, req2 = _coral(tmp_path, "coral", 1)
    now = {"box": ObjectPrior(mass_kg=0.40, friction=0.5)}  # this box's own prior: twice the volume
    _, _, beliefs = second._recall(second._memory(), req2, now, 16, 5, TrialLog(), 0.0)
    assert beliefs["box"].mass_kg == pytest.approx(0.60) and beliefs["box"].friction == pytest.approx(0.41)
