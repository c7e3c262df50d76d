"""System C's reasoner requests, hand-built without MuJoCo: CoRAL formulation requests, and the push-against-wall
scene its roles (priors, formulate, adapt) are checked on."""

from __future__ import annotations

from kintsugi.methods.coral.formulate import variable_docs
from kintsugi.methods.coral.types import (
    FixtureView,
    FormulationRequest,
    MarkerView,
    ObjectPrior,
    ObjectState,
    RobotView,
)
from kintsugi.sandbox import FUNCTIONS

ROBOT = RobotView(max_opening_m=0.1, finger_length_m=0.06, kp_n_per_m=600.0, force_limit_n=25.0, table_edge_x_m=0.3,
                  home_m=(-0.15, 0.0, 0.15))


def formulation_request(task: str, objects: list[ObjectState], fixtures: list[FixtureView] = (),
                        markers: list[MarkerView] = (), contact: bool = True) -> FormulationRequest:
    """A formulation request for `objects` (priors 0.2 kg, friction 0.5) beside `fixtures` and `markers`."""
    docs = variable_docs(None, [o.name for o in objects], [f.name for f in fixtures], [m.name for m in markers], contact)
    return FormulationRequest(task=task, objects=objects, fixtures=list(fixtures), markers=list(markers), robot=ROBOT,
                              priors={o.name: ObjectPrior(mass_kg=0.2, friction=0.5) for o in objects},
                              variables=docs, functions=dict(FUNCTIONS), contact_strategy=contact)


BOX = ObjectState(name="box", label="box", size_m=(0.06, 0.07, 0.05), pos_m=(0.03, 0.0, 0.025), yaw_deg=3.0,
                  upright_deg=0.0)
WALL = FixtureView(name="wall", lo_m=(0.2, -0.15, 0.0), hi_m=(0.23, 0.15, 0.06))
PUSH = formulation_request("Push the box against the wall and keep pressing it with a constant force of 5 N.", [BOX],
                           [WALL])
