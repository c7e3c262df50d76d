"""The conductor's head tracking (`Heads`): read once from a utensil seen lying free, then carried by the
hand's encoders and by continuity, so a turn to an absolute heading does not depend on a perceived head that
a hand over the utensil's middle can flip end to end."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from kintsugi.methods.agentchord.tops import Heads


@dataclass
class Seen:
    centroid: tuple
    axis: tuple
    extremes: dict = field(default_factory=dict)
    upright: bool | None = False
    visible: bool = True


@dataclass
class Hand:
    tcp_rpy_deg: tuple
    touching: dict

    @property
    def held(self) -> frozenset[str]:
        return frozenset(k for k, n in self.touching.items() if n == 2)


def _spoon(head_x: float) -> Seen:
    """A spoon lying along x; its head (the axis end nearer the centroid) at +x when head_x > 0."""
    return Seen(centroid=(0.4 + 0.03 * head_x, 0.0, 0.01), axis=(-1.0, 0.0, 0.0),
                extremes={"axis_pos": (0.5, 0.0, 0.01), "axis_neg": (0.3, 0.0, 0.01)})


def test_head_is_seeded_from_the_free_object_and_turns_with_the_hand() -> None:
    heads = Heads()
    heads.seed({"spoon": _spoon(-1.0), "cup": Seen((0.3, 0.2, 0.05), (0.0, 0.0, 1.0), upright=True)})
    assert heads.yaw_deg("spoon") == pytest.approx(180.0) or heads.yaw_deg("spoon") == pytest.approx(-180.0)
    assert heads.yaw_deg("cup") is None  # only lying objects have a head
    down = (180.0, 0.0, 0.0)  # gripper pointing down
    heads.follow({"right": Hand(down, {"spoon": 2})})
    heads.follow({"right": Hand((180.0, 0.0, 90.0), {"spoon": 2})})  # the hand turned 90 deg about the vertical
    assert heads.yaw_deg("spoon") == pytest.approx(-90.0, abs=1e-6)
    # Perceived with a flipped sign while it lies (the rule would flip it): continuity keeps the tracked head.
    heads.follow({"right": Hand((180.0, 0.0, 90.0), {})})
    heads.observe({"spoon": Seen((0.4, 0.0, 0.01), (0.0, 1.0, 0.0))})
    assert heads.yaw_deg("spoon") == pytest.approx(-90.0, abs=1e-6)
