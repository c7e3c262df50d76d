"""Draw the fixed camera's view of the peg task with OpenCV, with exact geometry known.

For tests and offline demos of perception and checks without MuJoCo: the
drawn geometry is the ground truth the measurements are scored against.
World: y to the right, z up, board surface at z = 0 hiding everything below.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.perception.types import CameraCalibration

SS = 4  # supersampling factor of the rasteriser


def default_calibration(width: int = 320, height: int = 240, px_per_mm: float = 2.0) -> CameraCalibration:
    """Board surface (z = 0) two thirds down the image, y = 0 at the image centre (cu = width / 2)."""
    return CameraCalibration(
        width=width, height=height, px_per_mm=px_per_mm, cu=width / 2.0, cv=float(round(height * 2 / 3)),
        y0_mm=0.0, z0_mm=0.0,
    )


class PegPose(StrictModel):
    """Peg drawn as a rectangle: bottom-centre (y, z) in mm, tilt in degrees (+ = top leans left)."""

    y: float
    z: float
    tilt_deg: float = 0.0
    width_mm: float = 40.0
    length_mm: float = 60.0

    def corners(self) -> np.ndarray:
        """(4, 2) corners in mm (y, z): bottom-left, bottom-right, top-right, top-left."""
        t = math.radians(self.tilt_deg)
        axis = np.array([-math.sin(t), math.cos(t)])
        perp = np.array([math.cos(t), math.sin(t)])
        b = np.array([self.y, self.z])
        hw = self.width_mm / 2.0
        return np.array([b - hw * perp, b + hw * perp, b + hw * perp + self.length_mm * axis, b - hw * perp + self.length_mm * axis])

    def visible_polygon(self, surface_z: float = 0.0) -> np.ndarray:
        """The part above the board surface (Sutherland-Hodgman clip against z >= surface_z)."""
        pts = self.corners()
        out = []
        for a, b in zip(pts, np.roll(pts, -1, axis=0)):
            a_in, b_in = a[1] >= surface_z, b[1] >= surface_z
            if a_in:
                out.append(a)
            if a_in != b_in:
                s = (surface_z - a[1]) / (b[1] - a[1])
                out.append(a + s * (b - a))
        return np.array(out).reshape(-1, 2)


class HoleGeom(StrictModel):
    """Hole drawn as a red rectangle on the board's front face, from the surface down to depth."""

    y: float
    width_mm: float = 42.0
    depth_mm: float = 30.0


def _raster(calib: CameraCalibration, pts_mm: np.ndarray) -> np.ndarray:
    """Boolean mask of pixels more than half covered by the polygon.

    cv2.fillPoly alone rounds vertices and fills inclusively (a 3 px wide
    rectangle becomes 4 px), which would bias every measurement by up to a
    pixel; supersampling then area-averaging makes the drawing unbiased.
    """
    px = np.array([calib.to_pixel(float(y), float(z)) for y, z in pts_mm])
    sub = np.round(px * SS - 0.5).astype(np.int32)  # pixel i covers [i, i + 1)
    canvas = np.zeros((calib.height * SS, calib.width * SS), np.uint8)
    cv2.fillPoly(canvas, [sub], 255, lineType=cv2.LINE_8)
    cover = cv2.resize(canvas, (calib.width, calib.height), interpolation=cv2.INTER_AREA)
    return cover > 127


def draw_scene(
    calib: CameraCalibration,
    peg: PegPose | None,
    hole: HoleGeom | None,
    *,
    seed: int = 0,
    noise: float = 6.0,
    peg_rgb: tuple[int, int, int] = (0, 230, 230),
    hole_rgb: tuple[int, int, int] = (210, 20, 25),
) -> np.ndarray:
    """RGB uint8 image: dark background, shaded noisy cyan peg, grey board over its lower part, red hole."""
    rng = np.random.default_rng(seed)
    h, w = calib.height, calib.width
    img = np.full((h, w, 3), 25, np.uint8)
    if peg is not None:
        layer = _raster(calib, peg.corners())
        shade = 0.75 + 0.25 * np.linspace(1.0, 0.0, w)[None, :] + rng.normal(0, 0.03, (h, w))
        colour = np.clip(np.array(peg_rgb)[None, None, :] * shade[:, :, None], 0, 255).astype(np.uint8)
        img[layer] = colour[layer]
    surface_v = calib.to_pixel(0.0, 0.0)[1]
    top_row = int(math.ceil(surface_v - 0.5))  # first pixel row whose centre (j + 0.5) is below the surface
    img[top_row:] = (128, 128, 128)
    if hole is not None:
        rect = np.array([[hole.y - hole.width_mm / 2, 0.0], [hole.y + hole.width_mm / 2, 0.0],
                         [hole.y + hole.width_mm / 2, -hole.depth_mm], [hole.y - hole.width_mm / 2, -hole.depth_mm]])
        img[_raster(calib, rect)] = hole_rgb
    if noise > 0:
        img = np.clip(img.astype(np.float32) + rng.normal(0, noise, img.shape), 0, 255).astype(np.uint8)
    return img


def visible_box_mm(peg: PegPose, surface_z: float = 0.0) -> tuple[float, float, float, float] | None:
    """(left y, right y, bottom z, top z) of the peg's part above the surface, or None if hidden."""
    poly = peg.visible_polygon(surface_z)
    if len(poly) < 3:
        return None
    return float(poly[:, 0].min()), float(poly[:, 0].max()), float(poly[:, 1].min()), float(poly[:, 1].max())


def peg_centred_at(center_y: float, z: float, tilt_deg: float = 0.0, **kw: float) -> PegPose:
    """A peg whose visible bounding-box centre is at y = center_y (bottom at height z)."""
    probe = PegPose(y=0.0, z=z, tilt_deg=tilt_deg, **kw)
    box = visible_box_mm(probe)
    if box is None:
        raise ValueError(f"a peg with its bottom at z={z} mm is entirely hidden by the board")
    return probe.model_copy(update={"y": center_y - (box[0] + box[1]) / 2.0})
