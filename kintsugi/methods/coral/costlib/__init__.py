"""The embedded formulation backend: cost code composed from a library of cost terms.

No lookup by task name. The instruction's words choose primitives and the objects' geometry fills them in:
which object the words name, whether it stands tall or lies flat, which fixture or marker it
goes to, which face to push on (the face turned away from the fixture), how high to grasp and
which side fits the gripper. Every skill writes its stages as functions of the cost language
(kintsugi.sandbox): the same untrusted-code path a model's reply takes, compiled and probed
before MPPI sees it. The code reads sizes and poses through variables (`box_half`,
`start_box_pos`, ...), never as baked numbers, so a stored episode's code fits a new trial
with a differently sized box. `knobs` are the weights and thresholds the code is written with;
the adaptation role refines them and the library writes the code again. Moves to a known pose also give
their goal as `<cost>_seed_<axis>` functions: the plan restarts there (see kintsugi.methods.coral.stages).

The instruction is read in the controlled language (`kintsugi.methods.coral.language`, docs/coral-language.md)
and planned as primitives (`kintsugi.methods.coral.plan`); here each segment of primitives is written by its
builder: `templates` holds the knobs and the shared cost-code templates, `scene` the pushed face's region, and
`grasp` (grasp, lift, carry, place), `push` (approach, push to a fixture, press), `slide` (push to a marker or a
distance, round a fixture), `turn` (rotate about an edge or over a fixture) and `edge` (push over the table edge,
grasp the overhang) write the stages.
"""

from __future__ import annotations

import re

from kintsugi.methods.coral.costlib.templates import DEFAULT_KNOBS, HELPERS, Plan, settle
from kintsugi.methods.coral.costlib.edge import pick_past_edge, push_over_edge
from kintsugi.methods.coral.costlib.grasp import pick, place
from kintsugi.methods.coral.costlib.push import press, push
from kintsugi.methods.coral.costlib.slide import avoid_code, slide
from kintsugi.methods.coral.costlib.turn import pivot, tip
from kintsugi.methods.coral.nouns import NotUnderstood
from kintsugi.methods.coral.plan import plan_instruction
from kintsugi.methods.coral.types import FormulationReply, FormulationRequest

__all__ = ["DEFAULT_KNOBS", "NotUnderstood", "compose"]


def compose(req: FormulationRequest, knobs: dict[str, float] | None = None) -> FormulationReply:
    """Instruction + scene -> staged cost code, stages, contact regions. Raises NotUnderstood.

    The instruction is read in the controlled language and planned into primitives
    (`kintsugi.methods.coral.plan`); each segment of primitives is written by its builder below."""
    k = {**DEFAULT_KNOBS, **(knobs or {})}
    cost_plan = plan_instruction(req)
    plan = Plan(code=[HELPERS])
    contact = req.contact_strategy
    avoid = {(seg.obj, f) for seg in cost_plan.segments if seg.builder == "slide" for f in seg.args["avoid"]}
    for name, f in sorted(avoid):
        plan.code.append(avoid_code(name, [f], next(x for x in req.objects if x.name == name)))
    objects = {o.name: o for o in req.objects}
    for seg in cost_plan.segments:
        mark = (len(plan.code), len(plan.stages))
        o = objects.get(seg.obj) if seg.obj else None
        others = [x for x in req.objects if o is None or x.name != o.name]
        a = seg.args
        if seg.builder == "push_to_fixture":
            push(plan, o, a["fixture"], a["axis"], a["sign"], k, contact)
        elif seg.builder == "press":
            k["hold_press_s"] = a["duration"]
            press(plan, o, a["fixture"], a["axis"], a["sign"], a["force"], k, contact)
        elif seg.builder == "pick":
            pick(plan, o, others, k, contact)
        elif seg.builder == "place":
            place(plan, o, others, a["marker"], k)
        elif seg.builder == "hold":
            settle(plan, "hold", a["seconds"], "closed", k)
        elif seg.builder == "push_over_edge":
            push_over_edge(plan, o, k, contact)
        elif seg.builder == "pick_overhang":
            if contact:
                pick_past_edge(plan, o, k)
            else:  # no contact strategy: no pinch under the overhang either; the planner finds the grasp
                pick(plan, o, others, k, contact=False)
                settle(plan, "hold", 0.5, "closed", k)
        elif seg.builder == "tip":
            tip(plan, o, a["axis"], a["sign"], k, contact)
        elif seg.builder == "pivot":
            pivot(plan, o, a["fixture"], a["axis"], a["sign"], k, contact)
        elif seg.builder == "slide":
            slide(plan, o, req, k, contact, origin=a["origin"], goal=a["goal"], avoid=a["avoid"], tol_m=a["tol"])
        else:  # pragma: no cover - plan and builders are written together
            raise NotUnderstood(f"no builder for {seg.builder}")
        _rename_clashes(plan, *mark)
    why = [f"Plan: {'; '.join(cost_plan.primitives)}."] + plan.why + [f"Note: {n}." for n in cost_plan.notes]
    names = _unique_stage_names(plan.stages)
    return FormulationReply(source=_dedup_params("\n\n\n".join(plan.code)), stages=names, regions=plan.regions,
                            knobs=k, reasoning=" ".join(why)[:4000])


def _unique_stage_names(stages: list) -> list:
    seen: dict[str, int] = {}
    out = []
    for st in stages:
        seen[st.name] = seen.get(st.name, 0) + 1
        out.append(st if seen[st.name] == 1 else st.model_copy(update={"name": f"{st.name}-{seen[st.name]}"}))
    return out


def _rename_clashes(plan: Plan, code_from: int, stages_from: int) -> None:
    """A segment that defines a function an earlier one defined (two slides, a withdraw after a withdraw) gets
    its own names: `name_2`, in its code and its stages."""
    defined = lambda chunks: set(re.findall(r"^def (\w+)\(", "\n".join(chunks), re.M))  # noqa: E731
    clash = {c for c in defined(plan.code[:code_from]) & defined(plan.code[code_from:]) if "_seed_" not in c}
    if not clash:
        return
    suffix = f"_{code_from}"
    pattern = re.compile(r"\b(" + "|".join(sorted(clash, key=len, reverse=True)) + r")(?=(_seed_\w+)?\()")
    plan.code[code_from:] = [pattern.sub(lambda m: m.group(1) + suffix, c) for c in plan.code[code_from:]]
    fields = ("cost", "done", "grip", "keep")
    for i in range(stages_from, len(plan.stages)):
        st = plan.stages[i]
        upd = {f: getattr(st, f) + suffix for f in fields if isinstance(getattr(st, f), str) and getattr(st, f) in clash}
        plan.stages[i] = st.model_copy(update=upd)


def _dedup_params(source: str) -> str:
    """A skill may name a variable twice when its terms share one (`box_pos`): keep the first."""
    def fix(m: re.Match) -> str:
        seen: list[str] = []
        for p in (x.strip() for x in m.group(2).split(",")):
            if p and p not in seen:
                seen.append(p)
        return f"def {m.group(1)}({', '.join(seen)}):"
    return re.sub(r"def (\w+)\(([^)]*)\):", fix, source)
