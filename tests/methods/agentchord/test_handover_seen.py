"""A handover counts only when both hands held the object at once with both finger pads each (read just before
the giving hand opens); a goal's handover never seen fails the goal check, so a one-pad hold at the release is
never reported as handed over."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from kintsugi.methods.agentchord.handing import Handing
from kintsugi.methods.agentchord.method import handed_objects


class Log:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def event(self, t: float, kind: str, detail: str) -> None:
        self.events.append((kind, detail))


def _hand(pads: int, opening: float = 0.03) -> SimpleNamespace:
    touching = {"block": pads} if pads else {}
    held = frozenset({"block"}) if pads == 2 or (pads == 1 and opening >= 0.01) else frozenset()
    return SimpleNamespace(touching=touching, held=held, gripper_opening_m=opening)


def _witness(left: SimpleNamespace, right: SimpleNamespace) -> Handing:
    h = Handing()
    h.log, h.robot = Log(), SimpleNamespace(sim_time=1.0, arm_state=lambda a: {"left": left, "right": right}[a])
    h.handover_goals = frozenset({"block"})
    h.witness_release({"action": "open_gripper", "arm": "left"})
    return h


@pytest.mark.parametrize(("left", "right", "seen"), [
    (_hand(2), _hand(2), True),
    (_hand(1), _hand(2), False),   # the giver holds it by one pad: both hands never held it with both pads
    (_hand(2), _hand(1), False),
    (_hand(2), _hand(2, opening=0.004), False),  # fingers shut on each other press both pads on its top
])
def test_a_handover_is_seen_only_with_both_pads_of_both_hands(left, right, seen: bool) -> None:  # noqa: ANN001
    h = _witness(left, right)
    assert h.seen_handovers() == ({"block"} if seen else set())
    assert h.handovers_done() is seen
    assert any(k == "handover not seen" for k, _ in h.log.events) is not seen


def test_a_release_by_a_hand_the_other_does_not_share_is_no_handover() -> None:
    h = _witness(_hand(2), _hand(0))
    assert h.__dict__.get("handed", {}) == {}
    assert not h.handovers_done()  # the goal asks for one, none was seen


def test_the_goals_handovers_are_read_from_its_literals() -> None:
    assert handed_objects(["handed_over(block, left, right)", "in_region(block, target)"]) == {"block"}
    assert handed_objects(["released(block)"]) == frozenset()
