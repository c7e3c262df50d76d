"""The "This robot" section of a prompt, written from the request's robot description.

The prompt files (`kintsugi/methods/recovery/prompts/*.md`) say nothing numeric about the robot or the
task: its sizes, clearance, springs and tolerances come from the request's
`RobotDescription` (built from the config the robot runs with), so
`--set peg.clearance_mm=1` is what the model is told. Trial randomization
(where the hole may be, how far the grasp may turn) is never stated. The
section goes into the user message, so the system prompt stays one fixed
text (cacheable by the endpoint) for every configuration.
"""

from __future__ import annotations

from pydantic import BaseModel

from kintsugi.worlds.peg.description import RobotDescription


def robot_section(request: BaseModel) -> str:
    """Markdown section stating the request's robot, ending in a blank line; "" when it has none."""
    robot = getattr(request, "robot", None)
    return f"# This robot\n{robot_facts(robot)}\n\n" if isinstance(robot, RobotDescription) else ""


def robot_facts(robot: RobotDescription) -> str:
    """The robot's description as prompt bullets (mm, N, degrees)."""
    v = robot.vision
    c = robot.hole_clearance_mm
    lever = robot.compliance_to_tip_mm
    return "\n".join([
        f"- The peg is the {robot.peg_shape} peg: {robot.peg_width_mm:g} mm wide in the image plane and "
        f"{robot.peg_length_mm:g} mm long. The hole is {c:g} mm wider than the peg ({robot.hole_width_mm:g} mm) "
        f"and {robot.hole_depth_mm:g} mm deep, so the peg must be within about ±{c / 2:g} mm of the hole centre "
        f"and nearly vertical to go in.",
        f"- From the wrist's compliance centre (at the commanded base pose) to the peg tip: {lever:g} mm. With its "
        f"tip held in the hole, moving the base by d mm in y turns the peg by about atan(d / {lever:g}).",
        f"- Wrist springs: z {robot.wrist_z_stiffness_n_per_mm:g} N/mm (the wrist force in each outcome is its "
        f"compression times this), roll {robot.wrist_roll_stiffness_nm_per_rad:g} Nm/rad.",
        f"- The taught contact presses the wrist {robot.contact_press_mm:.1f} mm ({robot.contact_press_n:.1f} N) "
        f"against the board surface; a tip that drops into the hole relieves much of that press, a tip caught on "
        f"the surface or the rim does not.",
        f"- A skill halts when the wrist is compressed more than {robot.compression_limit_mm:g} mm "
        f"({robot.compression_limit_n:g} N). A goal counts as reached within {robot.pose_tol_mm:g} mm.",
        f"- Vision check tolerances: 'on the hole' within ±{v.align_tol_mm:g} mm of the hole centre, 'vertical' "
        f"within ±{v.tilt_tol_deg:g}°, an inserted peg's visible top within {v.insert_top_tol_mm:g} mm of the "
        f"goal image's.",
    ])
