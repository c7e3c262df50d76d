"""Hand-built CoRAL formulation requests (no MuJoCo): a push-against-wall scene and a clutter pick scene."""

from __future__ import annotations

from kintsugi.methods.coral.types import MarkerView, ObjectState
from kintsugi.testing.push_requests import BOX, PUSH, ROBOT, WALL  # noqa: F401 - the push scene is the product's
from kintsugi.testing.push_requests import formulation_request as request

CUBES = [ObjectState(name=f"cube{i}", label="cube", size_m=(0.04, 0.04, 0.04), pos_m=p, yaw_deg=0.0, upright_deg=0.0)
         for i, p in enumerate([(0.17, -0.08, 0.02), (0.08, 0.0, 0.02), (0.08, -0.16, 0.02)])]
GREEN = BOX.model_copy(update={"pos_m": (0.08, -0.08, 0.025), "size_m": (0.045, 0.045, 0.05)})
DISC = MarkerView(name="goal", x_m=-0.05, y_m=0.18, radius_m=0.03)
CLUTTER = request("Pick up the green box from among the yellow cubes and put it down on the green disc.",
                  [GREEN, *CUBES], markers=[DISC])
