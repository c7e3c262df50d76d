"""The embedded verifier on `inside(capsule, tray)`: the `within` check reads the tray's footprint from its
perceived extent. The verifier's view of a seen object used to drop `extent`, so a capsule in the tray read as
unseen and the re-planning baselines re-planned the put-inside until their action budget ran out on every
coffee-tray trial (0/20 at both p)."""

from __future__ import annotations

from kintsugi.methods.agentchord.types import SeenArm, SeenObject, VerifyRequest
from kintsugi.methods.agentchord.verifier import embedded_verify

WITHIN = {"kind": "within", "point": {"entity": "capsule"}, "container": "tray", "margin": 0.01}
TRAY = SeenObject(name="tray", visible=True, centroid=(0.37, 0.0, 0.012), top_z=0.027, bottom_z=0.0, tilt_deg=90.0,
                  upright=False, extent=(0.30, 0.20, 0.027), extremes={}, axis=(1.0, 0.0, 0.0), n_points=900)


def _verify(x: float, y: float) -> bool:
    capsule = SeenObject(name="capsule", visible=True, centroid=(x, y, 0.03), top_z=0.045, bottom_z=0.015,
                         tilt_deg=0.0, upright=True, extent=(0.03, 0.034, 0.03), extremes={}, axis=(0.0, 0.0, 1.0),
                         n_points=150)
    arm = SeenArm(name="left", tcp_pos=(0.2, 0.3, 0.3), gripper_opening_m=0.1, gripper_closed=False, holding=[])
    return embedded_verify(VerifyRequest(task="put the capsule in the tray", subgoal="inside(capsule, tray)",
                                         constraints=[WITHIN], objects=[TRAY, capsule], arms=[arm])).success


def test_a_capsule_in_the_tray_is_inside() -> None:
    assert _verify(0.40, 0.05)  # near a corner of the 30 x 20 cm footprint, still inside


def test_a_capsule_beside_the_tray_is_not() -> None:
    assert not _verify(0.40, 0.14)
    assert not _verify(0.56, 0.0)
