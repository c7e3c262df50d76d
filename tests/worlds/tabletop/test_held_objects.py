"""What a hand holds, from its pads and its gripper: both pads on an object, or one pad on the only object
touched while the hand, commanded closed, stands open by at least HELD_MIN_OPENING_M."""

from __future__ import annotations

from kintsugi.worlds.tabletop.robot import HELD_MIN_OPENING_M, ArmState, held_objects


def test_both_pads_hold_whatever_the_opening() -> None:
    assert held_objects({"bottle": 2}, 0.06, True) == {"bottle"}
    assert held_objects({"towel": 2}, 0.002, True) == {"towel"}  # a pinched cloth corner


def test_one_pad_holds_only_when_the_object_keeps_the_closed_hand_open() -> None:
    assert held_objects({"bottle": 1}, 0.061, True) == {"bottle"}  # pinched off its equator, still in the hand
    assert held_objects({"cup": 1}, 0.0018, True) == frozenset()  # the fingers closed past it: it left the hand
    assert held_objects({"cup": 1}, HELD_MIN_OPENING_M - 1e-4, True) == frozenset()
    assert held_objects({"cup": 1}, 0.09, False) == frozenset()  # an open hand holds nothing by one pad
    assert held_objects({"cup": 1, "bottle": 1}, 0.05, True) == frozenset()  # two objects, one pad each: neither
    assert held_objects({"cup": 2, "bottle": 1}, 0.05, True) == {"cup"}


def test_the_arm_state_reads_the_same_rule() -> None:
    state = ArmState(joints_deg=(0.0,) * 6, tcp_pos=(0.4, 0.0, 0.2), tcp_rpy_deg=(0.0, 0.0, 0.0),
                     gripper_opening_m=0.06, gripper_closed=True, touching={"bottle": 1}, pad_force_n=30.0)
    assert state.held == {"bottle"}
    assert state.model_copy(update={"gripper_opening_m": 0.004}).held == frozenset()
