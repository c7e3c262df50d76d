"""Hand-built CoRAL formulation requests (no MuJoCo): a push-against-wall scene and a clutter pick scene."""

from __future__ import annotations

from kintsugi.methods.coral.types import FixtureView, FormulationRequest, MarkerView, ObjectPrior, ObjectState, RobotView
from kintsugi.methods.coral.formulate import variable_docs
from kintsugi.sandbox import FUNCTIONS

ROBOT = RobotView(max_opening_m=0.1, finger_length_m=0.06, kp_n_per_m=600.0, force_limit_n=25.0, table_edge_x_m=0.3,
                  home_m=(-0.15, 0.0, 0.15))


def request(task: str, objects: list[ObjectState], fixtures: list[FixtureView] = (), markers: list[MarkerView] = (),
            contact: bool = True) -> FormulationRequest:
    docs = variable_docs(None, [o.name for o in objects], [f.name for f in fixtures], [m.name for m in markers], contact)
    return FormulationRequest(task=task, objects=objects, fixtures=list(fixtures), markers=list(markers), robot=ROBOT,
                              priors={o.name: ObjectPrior(mass_kg=0.2, friction=0.5) for o in objects},
                              variables=docs, functions=dict(FUNCTIONS), contact_strategy=contact)


BOX = ObjectState(name="box", label="box", size_m=(0.06, 0.07, 0.05), pos_m=(0.03, 0.0, 0.025), yaw_deg=3.0,
                  upright_deg=0.0)
WALL = FixtureView(name="wall", lo_m=(0.2, -0.15, 0.0), hi_m=(0.23, 0.15, 0.06))
PUSH = request("Push the box against the wall and keep pressing it with a constant force of 5 N.", [BOX], [WALL])
CUBES = [ObjectState(name=f"cube{i}", label="cube", size_m=(0.04, 0.04, 0.04), pos_m=p, yaw_deg=0.0, upright_deg=0.0)
         for i, p in enumerate([(0.17, -0.08, 0.02), (0.08, 0.0, 0.02), (0.08, -0.16, 0.02)])]
GREEN = BOX.model_copy(update={"pos_m": (0.08, -0.08, 0.025), "size_m": (0.045, 0.045, 0.05)})
DISC = MarkerView(name="goal", x_m=-0.05, y_m=0.18, radius_m=0.03)
CLUTTER = request("Pick up the green box from among the yellow cubes and put it down on the green disc.",
                  [GREEN, *CUBES], markers=[DISC])
