"""The embedded formulation backend: cost code composed from a library of cost terms.

No lookup by task name. The instruction's words choose skills (pick / put down on / push
against / press with N / flip over / pivot against / push over the table edge, then pick) and
the objects' geometry fills them in:
which object the words name, whether it stands tall or lies flat, which fixture or marker it
goes to, which face to push on (the face turned away from the fixture), how high to grasp and
which side fits the gripper. Every skill writes its stages as functions of the cost language
(kintsugi.sandbox): the same untrusted-code path a model's reply takes, compiled and probed
before MPPI sees it. The code reads sizes and poses through variables (`box_half`,
`start_box_pos`, ...), never as baked numbers, so a stored episode's code fits a new trial
with a differently sized box. `knobs` are the weights and thresholds the code is written with;
the adaptation role refines them and the library writes the code again. Moves to a known pose also give
their goal as `<cost>_seed_<axis>` functions: the plan restarts there (see kintsugi.methods.coral.stages).

The library is split by skill: `scene` reads the instruction and the geometry, `templates` holds the knobs and the
cost-code templates, and `grasp`, `push`, `turn` and `edge` write the skills' stages.
"""

from __future__ import annotations

import re

from kintsugi.methods.coral.costlib.templates import DEFAULT_KNOBS, HELPERS, Plan, settle
from kintsugi.methods.coral.costlib.edge import pick_past_edge, push_over_edge
from kintsugi.methods.coral.costlib.grasp import pick, place
from kintsugi.methods.coral.costlib.push import press, push
from kintsugi.methods.coral.costlib.scene import NotUnderstood, duration_s, force_n, tall, target_object, toward, words
from kintsugi.methods.coral.costlib.turn import pivot, tip
from kintsugi.methods.coral.types import FormulationReply, FormulationRequest

__all__ = ["DEFAULT_KNOBS", "NotUnderstood", "compose"]


def compose(req: FormulationRequest, knobs: dict[str, float] | None = None) -> FormulationReply:
    """Instruction + scene -> staged cost code, stages, contact regions. Raises NotUnderstood."""
    k = {**DEFAULT_KNOBS, **(knobs or {})}
    text = " ".join(words(req.task))
    o = target_object(req)
    plan = Plan(code=[HELPERS])
    contact = req.contact_strategy
    others = [x for x in req.objects if x.name != o.name]
    if ("push" in text or "slide" in text) and "edge" in text and ("pick" in text or "lift" in text):
        push_over_edge(plan, o, k, contact)
        pick_past_edge(plan, o, k)
    elif "flip" in text or "tip" in text.split():
        fixture, axis, sign = toward(o, req)
        if not tall(o) and fixture is not None and any(w in text for w in ("curb", "wall", "fixture", "against")):
            pivot(plan, o, fixture, axis, sign, k, contact)
        else:
            tip(plan, o, axis, sign, k, contact)
    elif "push" in text or "press" in text:
        fixture, axis, sign = toward(o, req)
        if fixture is None:
            raise NotUnderstood("a push 'against' something needs a fixture in the scene; there is none")
        push(plan, o, fixture, axis, sign, k, contact)
        f = force_n(req.task)
        if duration_s(req.task) is not None:  # the instruction's duration, else the library's default
            k["hold_press_s"] = duration_s(req.task)
        if f is not None:
            press(plan, o, fixture, axis, sign, f, k, contact)
    elif "pick" in text or "lift" in text:
        pick(plan, o, others, k)
        marker = next((m for m in req.markers if any(w in text for w in ("disc", "goal", "marker", "put", "place"))),
                      None)
        if marker is not None and any(w in text for w in (" put ", " place", " on ", "down")):
            place(plan, o, others, marker.name, k)
        else:
            settle(plan, "hold", 0.5, "closed", k)
    else:
        raise NotUnderstood("no skill for this instruction: the library knows pick, put down on, push against, "
                            "press with a force, flip over, pivot against a fixture, and push over the table edge "
                            "then pick")
    return FormulationReply(source=_dedup_params("\n\n\n".join(plan.code)), stages=plan.stages, regions=plan.regions,
                            knobs=k, reasoning=" ".join(plan.why))


def _dedup_params(source: str) -> str:
    """A skill may name a variable twice when its terms share one (`box_pos`): keep the first."""
    def fix(m: re.Match) -> str:
        seen: list[str] = []
        for p in (x.strip() for x in m.group(2).split(",")):
            if p and p not in seen:
                seen.append(p)
        return f"def {m.group(1)}({', '.join(seen)}):"
    return re.sub(r"def (\w+)\(([^)]*)\):", fix, source)
