"""The towel: a MuJoCo flex cloth (flexcomp) on the table, its typed settings and its corners.

A square grid of `n x n` vertices, `spacing_m` apart, as an explicit ("direct") triangle
mesh: each quad's diagonal is mirrored about the towel's centre line, so that both
bottom corners (and both top corners) sit on a diagonal - a corner pinched across that
diagonal buckles into one ridge instead of folding along an edge. Elasticity (membrane +
bending) needs MuJoCo's discrete integrator, so a towel scene runs with its own
`<option>` (`TowelSection.scene_option`), leaving the rigid tasks' physics untouched.

Towel frame: origin at its centre, +u from the bottom edge to the top edge, +v from the
right edge to the left. Corners are named from the robot's side: with yaw 0, +u is world
+x (away from the robot), so the bottom edge is the one nearest the robot and the
bottom-left corner is the one at +y (the left arm's side).
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, model_validator

from kintsugi.core.config import Range, StrictModel
from kintsugi.worlds.tabletop.arm_model import f
from kintsugi.worlds.tabletop.scene import SceneExtra

TOWEL = "towel"
CORNERS = ("bottom_left", "bottom_right", "top_left", "top_right")
FLAT_BAND_M = 0.006
"""Cloud points within this of the lowest count as the cloth lying flat."""
CORNER_BAND_M = 0.003
CLOUD_POINTS = 20000
"""A cloth's cloud keeps this many points (the default thinning would drop corner pixels)."""


class TowelSection(StrictModel):
    """The cloth's mesh, material and contact settings, and the scene options it needs."""

    count: int = Field(9, ge=5, le=25)
    """Vertices per side (9 x 9 = 81 vertices, 243 degrees of freedom: a 20 cm towel at 2.5 cm)."""
    spacing_m: float = Field(0.025, gt=0.005, le=0.1)
    mass_kg: float = Field(0.05, gt=0)
    radius_m: float = Field(0.002, gt=0, le=0.01)
    """Collision radius (half the thickness) of the cloth's triangles."""
    friction: float = Field(0.4, gt=0)
    young_pa: float = Field(1e5, gt=0)
    poisson: float = Field(0.2, ge=0, lt=0.5)
    thickness_m: float = Field(0.002, gt=0)
    damping: float = Field(0.01, ge=0)
    contact_solref: tuple[float, float] = (0.004, 1.0)
    contact_solimp: tuple[float, float, float] = (0.95, 0.99, 0.0005)
    edge_solref: tuple[float, float] = (0.004, 1.0)
    rgba: tuple[float, float, float, float] = (0.85, 0.3, 0.35, 1.0)
    x_m: Range = (0.37, 0.39)
    y_m: Range = (-0.01, 0.01)
    yaw_deg: Range = (-3.0, 3.0)
    """Start pose of the towel's centre on the table; `none` uses the midpoints."""
    timestep_s: float = Field(0.002, gt=0, le=0.004)
    integrator: str = "discrete"
    tolerance: float = Field(1e-6, gt=0)

    @model_validator(mode="after")
    def _known_integrator(self) -> TowelSection:
        if self.integrator not in ("discrete", "implicitfast", "implicit", "Euler"):
            raise ValueError(f"towel.integrator {self.integrator!r} is not a MuJoCo integrator; "
                             "the cloth's elasticity needs 'discrete'")
        return self

    @property
    def side_m(self) -> float:
        return (self.count - 1) * self.spacing_m

    def scene_option(self) -> dict[str, str]:
        """`<option>` attributes of a towel scene (the cone, impratio and solver stay the world's)."""
        return {"timestep": f"{self.timestep_s:.6g}", "integrator": self.integrator,
                "tolerance": f"{self.tolerance:.6g}"}


def grid_uv(towel: TowelSection) -> np.ndarray:
    """(n*n, 2) vertex coordinates in the towel frame; vertex index = i * n + j, i along u, j along v."""
    n, s = towel.count, towel.spacing_m
    c = (n - 1) / 2
    return np.array([((i - c) * s, (j - c) * s) for i in range(n) for j in range(n)])


def grid_triangles(n: int) -> list[tuple[int, int, int]]:
    """Two triangles per quad, the diagonal mirrored about the centre line j = (n-1)/2 and about
    i = (n-1)/2, so each of the four corner quads is split by the diagonal through its corner."""
    tris = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1
            lower_j, lower_i = j < (n - 1) / 2, i < (n - 1) / 2
            if lower_j == lower_i:  # diagonal a-d
                tris += [(a, b, d), (a, d, c)]
            else:  # diagonal b-c
                tris += [(a, b, c), (b, d, c)]
    return tris


def corner_indices(n: int) -> dict[str, int]:
    """Vertex index of each named corner (bottom = i 0, left = j n-1: +v is the left)."""
    return {"bottom_right": 0, "bottom_left": n - 1, "top_right": (n - 1) * n, "top_left": n * n - 1}


def towel_xml(towel: TowelSection, x: float, y: float, yaw_deg: float) -> str:
    """The flexcomp, lying flat on the table at (x, y) turned by yaw."""
    points = grid_uv(towel)
    pts = " ".join(f(u, v, 0.0) for u, v in points)
    elems = " ".join(f"{a} {b} {c}" for a, b, c in grid_triangles(towel.count))
    yaw = math.radians(yaw_deg)
    quat = f(math.cos(yaw / 2), 0, 0, math.sin(yaw / 2))
    t = towel
    return f"""
    <flexcomp name="{TOWEL}" type="direct" dim="2" radius="{t.radius_m:.6g}" mass="{t.mass_kg:.6g}"
              pos="{f(x, y, t.radius_m + 0.0005)}" quat="{quat}" rgba="{f(*t.rgba)}"
              point="{pts}" element="{elems}">
      <contact condim="3" friction="{t.friction:.6g} 0.005 0.0001" selfcollide="auto"
               solref="{f(*t.contact_solref)}" solimp="{f(*t.contact_solimp)}"/>
      <edge equality="true" solref="{f(*t.edge_solref)}"/>
      <elasticity young="{t.young_pa:.6g}" poisson="{t.poisson:.6g}" thickness="{t.thickness_m:.6g}"
                  damping="{t.damping:.6g}" elastic2d="bend"/>
    </flexcomp>"""


def towel_extra(towel: TowelSection, x: float, y: float, yaw_deg: float) -> SceneExtra:
    return SceneExtra(worldbody=towel_xml(towel, x, y, yaw_deg), option=towel.scene_option(), flexes=(TOWEL,))


# --- features: what a method may see of the towel ----------------------------------

def _named_corners(points: np.ndarray) -> dict[str, np.ndarray]:
    """Name four corner points from the robot's side: the two nearest the robot (smallest x) are
    the bottom ones, and of each pair the one at larger y is the left."""
    by_x = points[np.argsort(points[:, 0], kind="stable")]
    out = {}
    for row, pair in (("bottom", by_x[:2]), ("top", by_x[2:])):
        left, right = (pair[0], pair[1]) if pair[0][1] >= pair[1][1] else (pair[1], pair[0])
        out[f"{row}_left"], out[f"{row}_right"] = left, right
    return out


def cloud_corners(cloud: np.ndarray, pixel_m: float = 0.0) -> dict[str, np.ndarray]:
    """The towel's four corners from its perceived cloud, from the part lying flat on the table (a
    pinched, lifted part would skew them). Where the cloth fills a corner of its minimum-area
    rectangle (a flat, square towel), that rectangle corner: fitted to every edge point, it is
    finer than a pixel. Elsewhere (a dragged, no longer square towel) the points extreme along
    that diagonal, averaged over a thin band, moved onto the extreme and half a pixel
    (`pixel_m`, the top view's footprint on the table) outwards."""
    import cv2

    flat = cloud[cloud[:, 2] <= cloud[:, 2].min() + FLAT_BAND_M]
    pts = flat if len(flat) >= 10 else cloud
    xy = pts[:, :2]
    rect = cv2.minAreaRect(xy.astype(np.float32))
    centre = np.array(rect[0], float)
    picks = []
    for b in cv2.boxPoints(rect):
        near = np.linalg.norm(xy - b, axis=1) <= 0.75 * max(pixel_m, 1e-3)
        if near.any():  # the cloth fills the rectangle's corner: the fit to every edge point is best
            picks.append([float(b[0]), float(b[1]), float(pts[near, 2].mean())])
            continue
        d = (b - centre) / max(float(np.linalg.norm(b - centre)), 1e-9)
        t = xy @ d
        sel = t >= t.max() - CORNER_BAND_M
        m = xy[sel].mean(axis=0)
        # the extreme pixel's centre lies up to half a pixel inside the edge along x and y
        c = m + (t.max() - m @ d + 0.5 * pixel_m * (abs(d[0]) + abs(d[1]))) * d
        picks.append([c[0], c[1], float(pts[sel, 2].mean())])
    return _named_corners(np.array(picks))


def corner_features(name: str, cloud: np.ndarray, corners: dict[str, np.ndarray], note: str = ""):  # noqa: ANN201
    """ObjectFeatures of a cloth: centroid, PCA axis and extent, top / bottom points, and its corners
    as extremes `corner_bottom_left`, ... (no primitive fits a cloth: fit='raw')."""
    from kintsugi.perception.features import ObjectFeatures, sign_normalized

    if len(cloud) < 10:
        return ObjectFeatures(name=name, visible=False, n_points=len(cloud), fit="raw", note="too few points")
    c = cloud.mean(axis=0)
    q = cloud - c
    w, v = np.linalg.eigh(q.T @ q / len(cloud))
    axis = sign_normalized(v[:, -1])
    proj = q @ v[:, ::-1]
    extent = tuple(float(e) for e in proj.max(axis=0) - proj.min(axis=0))
    ex = {"top": cloud[int(np.argmax(cloud[:, 2]))], "bottom": cloud[int(np.argmin(cloud[:, 2]))]}
    ex |= {f"corner_{k}": p for k, p in corners.items()}
    v3 = lambda a: (float(a[0]), float(a[1]), float(a[2]))  # noqa: E731
    return ObjectFeatures(name=name, visible=True, n_points=len(cloud), fit="raw", note=note,
                          centroid=v3(c), raw_centroid=v3(c), axis=v3(axis), extent=extent,
                          extremes={k: v3(p) for k, p in ex.items()})


def truth_corner_features(name: str, vertices: np.ndarray, n: int):  # noqa: ANN201
    """The same features from the simulator's vertex positions (the `truth` perception option)."""
    corners = {k: vertices[i] for k, i in corner_indices(n).items()}
    return corner_features(name, vertices, corners, note="ground truth")
