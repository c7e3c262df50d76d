"""Segmentation and depth of a camera from ONE render pass.

`mujoco.Renderer` gives segmentation and depth in two separate passes (each a
full draw and read-back). With segment colouring on, a single draw already
holds both: the colour buffer encodes each pixel's geom and the depth buffer its
distance. Reading both back at once halves the render cost of perception.
The output matches `mujoco.Renderer` exactly (tested): (H, W, 2) int32
(object id, object type), -1 for background; (H, W) float32 z-depth in metres.
"""

from __future__ import annotations

import mujoco
import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.perception.cloud import CameraModel, View, camera_id


class SegDepthRenderer:
    """Offscreen renderer of seg + depth views at a fixed image size (EGL/OSMesa/GLFW via MUJOCO_GL)."""

    def __init__(self, model: mujoco.MjModel, width: int = 320, height: int = 240, max_geom: int = 10000) -> None:
        self._gl = None
        self._ctx = None
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ConfigError(
                f"{width}x{height} exceeds the model's offscreen buffer "
                f"{model.vis.global_.offwidth}x{model.vis.global_.offheight} (set <visual><global offwidth/offheight>)"
            )
        self.model, self.width, self.height = model, width, height
        self._gl = mujoco.GLContext(width, height)
        self._gl.make_current()
        self._ctx = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._ctx)
        self._ctx.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR  # reversed z: precise far away
        self._scene = mujoco.MjvScene(model, maxgeom=max_geom)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self._scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._rgb = np.empty((height, width, 3), np.uint8)
        self._depth = np.empty((height, width), np.float32)

    def view(self, data: mujoco.MjData, camera: str | int) -> View:
        """Calibration, depth and segmentation of one camera at the data's current state."""
        if self._ctx is None:
            raise ConfigError("SegDepthRenderer was used after close()")
        cam_id = camera_id(self.model, camera)
        calibration = CameraModel.from_mujoco(self.model, data, cam_id, self.width, self.height)
        self._camera.fixedcamid = cam_id
        mujoco.mjv_updateScene(
            self.model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene
        )
        self._gl.make_current()
        mujoco.mjr_render(self._rect, self._scene, self._ctx)
        mujoco.mjr_readPixels(self._rgb, self._depth, self._rect, self._ctx)
        return View(calibration, self._metric_depth()[::-1].copy(), self._segmentation()[::-1].copy())

    def _metric_depth(self) -> np.ndarray:
        """Undo the reversed-z perspective depth mapping (as mujoco.Renderer does, in float64)."""
        extent = self.model.stat.extent
        near = np.float32(self.model.vis.map.znear * extent)
        far = np.float32(self.model.vis.map.zfar * extent)
        c = -(far + near) / (far - near)
        d = -(np.float32(2) * far * near) / (far - near)
        c, d = np.float32(-0.5) * c - np.float32(0.5), np.float32(-0.5) * d
        return (d / (self._depth.astype(np.float64) + c)).astype(np.float32)

    def _segmentation(self) -> np.ndarray:
        n = self._scene.ngeom
        rgb = self._rgb
        segid = rgb[..., 0] | (rgb[..., 1].astype(np.int32) << 8)  # 0 = background, else geom segid + 1
        if n >= 2**16 - 1:
            segid |= rgb[..., 2].astype(np.int32) << 16
        table = np.full((n + 1, 2), -1, np.int32)
        for g in self._scene.geoms[:n]:
            if g.segid >= 0:
                table[g.segid + 1] = (g.objid, g.objtype)
        return table[np.minimum(segid, n)]

    def close(self) -> None:
        """Free the GL resources (also on garbage collection)."""
        if self._ctx is not None and self._gl is not None:
            self._gl.make_current()
            self._ctx.free()
        self._ctx = None
        if self._gl is not None:
            self._gl.free()
        self._gl = None

    def __enter__(self) -> SegDepthRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # the GL display may already be gone at interpreter exit
            pass


def render_view(renderer: mujoco.Renderer | SegDepthRenderer, data: mujoco.MjData, camera: str | int) -> View:
    """Segmentation and depth of one camera with its calibration.

    With a `SegDepthRenderer`, one pass; with a `mujoco.Renderer` (e.g. one that
    also renders RGB), one scene update and two passes.
    """
    if isinstance(renderer, SegDepthRenderer):
        return renderer.view(data, camera)
    model = renderer.model
    cam = CameraModel.from_mujoco(model, data, camera, renderer.width, renderer.height)
    renderer.update_scene(data, camera_id(model, camera))
    try:
        renderer.enable_segmentation_rendering()
        seg = renderer.render()
        renderer.enable_depth_rendering()
        depth = renderer.render()
    finally:
        renderer.disable_depth_rendering()
        renderer.disable_segmentation_rendering()
    return View(cam, depth, seg)
