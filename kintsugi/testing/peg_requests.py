"""System A's reasoner requests, hand-built without a simulator: a peg-in-hole judge (with a terminal and a goal
image), an analysis and a plan. Drive a backend, a model server or the peg recovery's roles with them."""

from __future__ import annotations

import struct
import zlib

import kintsugi.methods.recovery.roles  # noqa: F401 - registers judge, analyze and plan (`ask` needs them)
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    JudgeRequest,
    PlanRequest,
    SkillOutcome,
)
from kintsugi.perception.types import CameraCalibration, CheckResult, Pose


def tiny_png(value: int = 0) -> bytes:
    """A valid 2x2 grey PNG; `value` makes distinct images distinguishable."""

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes([value, value]) for _ in range(2))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


TERMINAL_PNG, GOAL_PNG = tiny_png(10), tiny_png(200)
CAL = CameraCalibration(width=640, height=480, px_per_mm=4.0, cu=320, cv=240, y0_mm=0, z0_mm=0)
GOALS = {"fit": Pose(y=10.0, z=5.0), "align": Pose(y=12.0, z=5.0), "insert": Pose(y=12.0, z=-20.0)}
SKILLS = {"fit": ["y"], "align": ["y"], "insert": ["z"]}


def outcome(skill: str = "align") -> SkillOutcome:
    return SkillOutcome(skill=skill, goal=GOALS[skill], terminal=Pose(y=11.2, z=4.0), reached_goal=False,
                        timed_out=False, compression_limit=False, wrist_force_z_n=1.5, image_png=TERMINAL_PNG)


def judge_request(goal_image: bool = True) -> JudgeRequest:
    return JudgeRequest(task="insert the round peg", outcome=outcome("insert"),
                        checks=[CheckResult(name="pose", passed=False, message="pose error 3.1 mm")],
                        success_criteria="peg at least 10 mm inside the hole",
                        goal_image_png=GOAL_PNG if goal_image else None, calibration=CAL)


GOOD_ANALYSIS = AnalyzeReply(what_happened="peg left of hole", why="p_ey was too small",
                             how_to_recover="move align goal right 2 mm", restart_from="align",
                             motions=[{"skill": "align", "axis": "y", "delta": 2.0}])


def analyze_request() -> AnalyzeRequest:
    return AnalyzeRequest(task="insert the round peg", outcome=outcome(),
                          checks=[CheckResult(name="vision", passed=False, message="p_ey was too small.")],
                          verdict=JudgeReply(success=False, explanation="left of hole"), goals=GOALS, history=[],
                          calibration=CAL, max_step_mm=5.0, skills=SKILLS)


def plan_request() -> PlanRequest:
    return PlanRequest(task="insert the round peg", analysis=GOOD_ANALYSIS, goals=GOALS, skills=SKILLS,
                       max_step_mm=5.0, workspace={"y": (-40.0, 40.0), "z": (-40.0, 30.0)})
