"""The embedded verifier on an object perception gave no axis (a cube): "upright" is judged by the composer's
own rule (as tall as it is long), as a look would; before, it read as unseen and failed every DoReMi check on
handover-block's block (0/20)."""

from __future__ import annotations

from kintsugi.methods.agentchord.types import SeenArm, SeenObject, VerifyRequest
from kintsugi.methods.agentchord.verifier import embedded_verify

UP = {"kind": "upright", "object": "block", "tol_deg": 15}


def _block(height: float) -> SeenObject:
    return SeenObject(name="block", visible=True, centroid=(0.4, 0.2, 0.15), top_z=0.15 + height / 2,
                      bottom_z=0.15 - height / 2, tilt_deg=None, upright=None, extent=(0.05, 0.05, height),
                      extremes={}, axis=None, n_points=120)


def _verify(block: SeenObject) -> bool:
    arm = SeenArm(name="left", tcp_pos=(0.4, 0.2, 0.15), gripper_opening_m=0.05, gripper_closed=True,
                  holding=["block"])
    return embedded_verify(VerifyRequest(task="hand the block over", subgoal="lift", constraints=[UP],
                                         objects=[block], arms=[arm])).success


def test_a_cube_without_an_axis_is_upright() -> None:
    assert _verify(_block(0.05))


def test_a_flat_slab_without_an_axis_is_not() -> None:
    assert not _verify(_block(0.01))
