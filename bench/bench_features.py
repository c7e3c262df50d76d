"""Object features from seg+depth renders: time per view, and centroid accuracy against ground truth.

    .venv/bin/python bench/bench_features.py [--repeats 40] [--seed 0]

A tabletop scene built here (table plane, bottle, hollow cup, plate, block, ball,
open tray, and two 7-link arms of capsules for realistic render load), two
cameras (top, front) at 320x240. Each repeat draws new object poses (upright or
lying bottle and cup, random yaw), then times, in rotating order:
  render   - seg + depth of one camera: one pass (`SegDepthRenderer`) and, for comparison,
             mujoco.Renderer's two passes (`render_view` on a mujoco.Renderer)
  cloud    - fused clouds of every object from both views (`object_clouds`)
  features - per object: raw (no known shape), primitive fit, primitive fit + views check
Prints medians and the machine; target <= 15 ms per view (render + that view's share of
cloud + features of every object). Ground truth is read only to score accuracy.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np

from kintsugi.perception.features import (
    Primitive,
    SegDepthRenderer,
    body_geom_ids,
    features,
    object_clouds,
    render_view,
)

W, H = 320, 240
TARGET_MS = 15.0
CAMERAS = ("top", "front")


def cup_geoms(r: float, h: float, wall: float, walls: int = 16) -> str:
    """A hollow cup: a floor disc and a ring of thin boxes, open at the top."""
    half_w = (r - wall / 2) * math.tan(math.pi / walls) + 0.001
    out = f'<geom type="cylinder" size="{r} {wall / 2}" pos="0 0 {-h + wall / 2}"/>'
    for k in range(walls):
        a = 2 * math.pi * k / walls
        x, y = (r - wall / 2) * math.cos(a), (r - wall / 2) * math.sin(a)
        out += (f'<geom type="box" size="{wall / 2} {half_w} {h - wall / 2}" pos="{x} {y} {wall / 2}" '
                f'euler="0 0 {math.degrees(a)}"/>')
    return out


def tray_geoms(hx: float, hy: float, hz: float, wall: float) -> str:
    """A tray: a base plate and four rims, open at the top."""
    out = f'<geom type="box" size="{hx} {hy} {wall / 2}" pos="0 0 {-hz + wall / 2}"/>'
    for sx, sy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        size = (wall / 2, hy, hz) if sx else (hx, wall / 2, hz)
        out += f'<geom type="box" size="{size[0]} {size[1]} {size[2]}" pos="{sx * (hx - wall / 2)} {sy * (hy - wall / 2)} 0"/>'
    return out


OBJECTS = {  # name: (geoms xml, primitive, can lie down)
    "bottle": ('<geom type="cylinder" size="0.035 0.11"/>', Primitive.cylinder(0.035, 0.11), True),
    "cup": (cup_geoms(0.04, 0.05, 0.004), Primitive.cylinder(0.04, 0.05, wall=0.004), True),
    "plate": ('<geom type="cylinder" size="0.1 0.008"/>', Primitive.cylinder(0.1, 0.008), False),
    "block": ('<geom type="box" size="0.03 0.03 0.03"/>', Primitive.box(0.03, 0.03, 0.03), False),
    "ball": ('<geom type="sphere" size="0.025"/>', Primitive.sphere(0.025), False),
    "tray": (tray_geoms(0.1, 0.07, 0.012, 0.006), Primitive.box(0.1, 0.07, 0.012, wall=0.006), False),
}
SLOTS = [(x, y) for x in (-0.2, 0.15) for y in (-0.3, 0.0, 0.3)]  # far enough apart for any pose


def _arm(name: str, y: float) -> str:
    links = ""
    for i in range(7):
        links += f'<body name="{name}{i}" pos="0 0 {0.12 if i else 0.3}" euler="{20 if i % 2 else -15} 0 0">'
        links += f'<geom type="capsule" size="0.035" fromto="0 0 0 0 0 0.12" rgba=".7 .7 .7 1"/>'
    return f'<body name="{name}" pos="-0.45 {y} 0">' + links + "</body>" * 8


def scene_xml() -> str:
    bodies = "".join(
        f'<body name="{n}"><freejoint/>{g}</body>' for n, (g, _, _) in OBJECTS.items()
    )
    return f"""
<mujoco>
  <visual><global offwidth="{W}" offheight="{H}"/></visual>
  <default><geom rgba=".3 .5 .8 1"/></default>
  <worldbody>
    <light pos="0 0 2"/>
    <geom name="table" type="plane" size="1 1 0.01"/>
    {bodies}{_arm("left", 0.3)}{_arm("right", -0.3)}
    <camera name="top" pos="0 0 1.0" xyaxes="1 0 0 0 1 0" fovy="55"/>
    <camera name="front" pos="0.8 0 0.5" xyaxes="0 1 0 -0.5 0 0.866" fovy="55"/>
  </worldbody>
</mujoco>"""


def place(model: mujoco.MjModel, data: mujoco.MjData, rng: np.random.Generator) -> None:
    """New poses: objects on shuffled slots, random yaw; bottle and cup lying half of the time."""
    slots = rng.permutation(len(SLOTS))
    for k, (name, (_, prim, can_lie)) in enumerate(OBJECTS.items()):
        qadr = model.jnt_qposadr[model.body_jntadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)]]
        x, y = SLOTS[slots[k]]
        yaw = rng.uniform(-math.pi, math.pi)
        lying = can_lie and rng.random() < 0.5
        if prim.kind == "cylinder":
            z = prim.radius if lying else prim.half_length
        elif prim.kind == "box":
            z = prim.half_extents[2]
        else:
            z = prim.radius
        q_yaw = np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
        q_lie = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0]) if lying else np.array([1.0, 0, 0, 0])
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, q_yaw, q_lie)
        data.qpos[qadr : qadr + 7] = [x + rng.uniform(-0.02, 0.02), y + rng.uniform(-0.02, 0.02), z, *quat]
    mujoco.mj_forward(model, data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=40, help="scene draws (each timed once per stage)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(
        f"machine: {platform.platform()} | {platform.processor() or platform.machine()} | "
        f"{os.cpu_count()} CPUs | Python {sys.version.split()[0]} | mujoco {mujoco.__version__} | "
        f"load avg {os.getloadavg()[0]:.2f}"
    )
    model = mujoco.MjModel.from_xml_string(scene_xml())
    data = mujoco.MjData(model)
    ids = {n: body_geom_ids(model, n) for n in OBJECTS}
    rng = np.random.default_rng(args.seed)
    renderers = {"render": SegDepthRenderer(model, W, H), "render2": mujoco.Renderer(model, H, W)}

    t: dict[str, list[float]] = {k: [] for k in ("render", "render2", "cloud", "raw", "fit", "fit+views")}
    errs: dict[str, list[float]] = {k: [] for k in ("raw", "fit", "fit+views")}
    fitted = {"fit": 0, "fit+views": 0}
    n_feat = 0
    place(model, data, rng)
    for renderer in renderers.values():  # warm-up (GL context, caches)
        for cam in CAMERAS:
            render_view(renderer, data, cam)
    for rep in range(args.repeats):
        place(model, data, rng)
        views = []
        for kind in ("render", "render2")[rep % 2 :] + ("render", "render2")[: rep % 2]:
            for cam in CAMERAS:
                t0 = time.perf_counter()
                view = render_view(renderers[kind], data, cam)
                t[kind].append(time.perf_counter() - t0)
                if kind == "render":
                    views.append(view)
        t0 = time.perf_counter()
        clouds = object_clouds(views, ids)
        t["cloud"].append(time.perf_counter() - t0)
        modes = ["raw", "fit", "fit+views"]
        for name, (_, prim, _) in OBJECTS.items():
            truth = data.xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)]
            for mode in modes[rep % 3 :] + modes[: rep % 3]:
                t0 = time.perf_counter()
                f = features(
                    name, clouds[name], None if mode == "raw" else prim, views=views if mode == "fit+views" else None
                )
                t[mode].append(time.perf_counter() - t0)
                if f.visible:
                    errs[mode].append(float(np.linalg.norm(np.array(f.centroid) - truth)))
                    if mode != "raw":
                        fitted[mode] += f.fit == "primitive"
            n_feat += 1
    for renderer in renderers.values():
        renderer.close()

    ms = {k: 1e3 * statistics.median(v) for k, v in t.items()}
    k = len(OBJECTS)
    per_view = ms["render"] + (ms["cloud"] + k * ms["fit+views"]) / len(CAMERAS)
    per_view_two = ms["render"] + (ms["cloud"] + 2 * ms["fit+views"]) / len(CAMERAS)
    print(f"\n{args.repeats} scene draws, {k} objects, {len(CAMERAS)} views at {W}x{H}; medians\n")
    print("| stage | median |")
    print("|---|---|")
    print(f"| render: seg + depth, one view, one pass (SegDepthRenderer) | {ms['render']:.2f} ms |")
    print(f"| render: seg + depth, one view, two passes (mujoco.Renderer) | {ms['render2']:.2f} ms |")
    print(f"| cloud: all {k} objects from both views | {ms['cloud']:.2f} ms |")
    print(f"| features, one object, raw (no known shape) | {ms['raw']:.2f} ms |")
    print(f"| features, one object, primitive fit | {ms['fit']:.2f} ms |")
    print(f"| features, one object, primitive fit + views check | {ms['fit+views']:.2f} ms |")
    print(f"| **per view, all {k} objects** (one-pass render + half of cloud + features) | **{per_view:.2f} ms** |")
    print(f"| per view, 2 watched objects | {per_view_two:.2f} ms |")
    print(f"\ntarget <= {TARGET_MS:.0f} ms per view: {'ok' if per_view <= TARGET_MS else 'MISSED'} with all {k} objects, "
          f"{'ok' if per_view_two <= TARGET_MS else 'MISSED'} with 2\n")
    print("centroid error vs ground truth (mm), over every visible object of every draw:\n")
    print("| features | n | median | p90 | max | primitive fits |")
    print("|---|---|---|---|---|---|")
    for mode, e in errs.items():
        mm = np.array(e) * 1e3
        share = f"{fitted[mode]}/{n_feat}" if mode in fitted else "-"
        print(f"| {mode} | {len(mm)} | {np.median(mm):.1f} | {np.percentile(mm, 90):.1f} | {mm.max():.1f} | {share} |")


if __name__ == "__main__":
    main()
