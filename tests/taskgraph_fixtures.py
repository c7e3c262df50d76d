"""A test vocabulary and a small hand-made pour graph for the taskgraph tests (no task code); system B's
hand-made pour requests come from `kintsugi.testing.pour_requests`."""

from __future__ import annotations

from typing import Any, Literal

from kintsugi.core.config import StrictModel
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.taskgraph.vocabulary import Vocabulary
from kintsugi.testing.pour_requests import (  # noqa: F401 - system B's requests, for the tests to import here
    POUR_GOAL, POUR_TEXT, arranger_request, composer_request, seen_scene)


class ArmArgs(StrictModel):
    arm: Literal["left", "right"]


class GraspArgs(StrictModel):
    arm: Literal["left", "right"]
    object: Literal["bottle", "cup"]


class MoveToObjArgs(GraspArgs):
    x_offset: float = 0.0
    y_offset: float = 0.0
    z_offset: float = 0.0


def rotate_args(args: dict[str, Any]) -> None:
    """A plain-callable validator, to show both forms are accepted."""
    if set(args) != {"arm", "angle_deg"}:
        raise ValueError("rotate_eef takes exactly arm and angle_deg")
    if not -180.0 <= float(args["angle_deg"]) <= 180.0:
        raise ValueError("angle_deg must be within [-180, 180]")


VOCAB = Vocabulary(
    actions={
        "grasp": GraspArgs,
        "move_to_obj": MoveToObjArgs,
        "rotate_eef": rotate_args,
        "open_gripper": ArmArgs,
        "close_gripper": ArmArgs,
        "back": ArmArgs,
        "wait": None,
    },
    objects=frozenset({"bottle", "cup"}),
    features=frozenset({"centroid", "axis", "n_points", "top"}),
)


def act(name: str, **args: Any) -> dict[str, Any]:
    return {"name": name, "args": args}


def pour_graph_data() -> dict[str, Any]:
    """Grasp a bottle, carry it over a cup, tilt, restore. Two recovery branches: one forward, one backward."""
    bottle_in_hand = {"kind": "detached", "arm": "right", "object": "bottle", "tol": 0.08}
    return {
        "task": "pour water from the bottle into the cup",
        "start": "home",
        "goal": "done",
        "nodes": [
            {"id": "home", "description": "arms at home", "gripper": {"right": "open"}},
            {"id": "grasped", "description": "bottle in the right hand", "gripper": {"right": "closed"},
             "constraints": [{"kind": "near", "a": {"entity": "right"}, "b": {"entity": "bottle"}, "tol": 0.05}]},
            {"id": "over_cup", "description": "bottle above the cup",
             "constraints": [
                 {"kind": "above", "a": {"entity": "bottle"}, "b": {"entity": "cup", "feature": "top"}, "min_gap": 0.05},
                 {"kind": "misaligned", "a": {"entity": "bottle"}, "b": {"entity": "cup"}, "tol": 0.03}]},
            {"id": "poured", "description": "bottle tilted over the cup",
             "constraints": [{"kind": "tilted", "object": "bottle", "min_deg": 60}]},
            {"id": "done", "description": "bottle upright again",
             "constraints": [{"kind": "upright", "object": "bottle", "tol_deg": 10}]},
            {"id": "regrasp", "kind": "recovery", "description": "bottle picked up again", "gripper": {"right": "closed"}},
            {"id": "reset", "kind": "recovery", "description": "arms home, to start over"},
        ],
        "edges": [
            {"id": "e_grasp", "source": "home", "target": "grasped", "cost": 40,
             "actions": [act("grasp", arm="right", object="bottle")],
             "monitors": [{"id": "m_miss", "failure_mode": "missed_grasp",
                           "check": {"kind": "not_grasped", "arm": "right", "min_opening": 0.01},
                           "window": 3, "recovery": "r_retry"}]},
            {"id": "e_carry", "source": "grasped", "target": "over_cup", "cost": 60,
             "actions": [act("move_to_obj", arm="right", object="cup", z_offset=0.15)],
             "path_constraints": [{"kind": "upright", "object": "bottle", "tol_deg": 20}],
             "monitors": [
                 {"id": "m_drop", "failure_mode": "drop", "check": bottle_in_hand, "margin": 0.01,
                  "window": 3, "recovery": "r_pick"},
                 {"id": "m_cup", "failure_mode": "object_moved",
                  "check": {"kind": "drift", "point": {"entity": "cup"}, "tol": 0.03, "axes": "xy"},
                  "window": 5, "recovery": "r_reset"}]},
            {"id": "e_tilt", "source": "over_cup", "target": "poured", "cost": 30,
             "actions": [act("rotate_eef", arm="right", angle_deg=100)],
             "monitors": [{"id": "m_vis", "failure_mode": "tracking_lost",
                           "check": {"kind": "visibility", "object": "bottle", "n_min": 50}}]},
            {"id": "e_restore", "source": "poured", "target": "done", "cost": 30,
             "actions": [act("rotate_eef", arm="right", angle_deg=-100)]},
            {"id": "r_retry", "kind": "recovery", "source": "home", "target": "home", "cost": 20,
             "actions": [act("open_gripper", arm="right"), act("back", arm="right")]},
            {"id": "r_pick", "kind": "recovery", "source": "grasped", "target": "regrasp", "cost": 50,
             "actions": [act("grasp", arm="right", object="bottle")]},
            {"id": "r_merge", "kind": "recovery", "source": "regrasp", "target": "grasped", "cost": 5,
             "actions": [act("move_to_obj", arm="right", object="bottle", z_offset=0.1)]},
            {"id": "r_reset", "kind": "recovery", "source": "grasped", "target": "reset", "cost": 30,
             "actions": [act("open_gripper", arm="right")]},
            {"id": "r_home", "kind": "recovery", "source": "reset", "target": "home", "cost": 20,
             "actions": [act("back", arm="right")]},
        ],
    }


def pour_graph() -> TaskGraph:
    return TaskGraph.from_data(pour_graph_data(), VOCAB)


# --- system B's roles on a hand-made observation (no simulator) -----------------------------------------

def tabletop_vocab():
    from kintsugi.methods.agentchord.vocab import tabletop_vocabulary

    return tabletop_vocabulary(("bottle", "cup"))
