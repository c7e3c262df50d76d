"""Camera images at the size a role needs: PNGs larger than that are scaled down (OpenCV, area filter)."""

from __future__ import annotations

import cv2
import numpy as np


def png_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG header, or None when `data` is no PNG."""
    if data[:8] != b"\x89PNG\r\n\x1a\n" or len(data) < 24:
        return None
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def fit_png(data: bytes, max_px: int) -> tuple[bytes, str]:
    """`data` with its longer side at most `max_px`, and a note for the model when it was scaled ("" if not)."""
    size = png_size(data)
    if size is None or max(size) <= max_px:
        return data, ""
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        return data, ""
    w, h = size
    scale = max_px / max(w, h)
    small = cv2.resize(image, (max(1, round(w * scale)), max(1, round(h * scale))), interpolation=cv2.INTER_AREA)
    ok, out = cv2.imencode(".png", small)
    if not ok:
        return data, ""
    return out.tobytes(), (f"shown at {small.shape[1]}x{small.shape[0]} px, scaled by {scale:.3g} from the "
                           f"{w}x{h} px camera image the calibration describes")


def image_tokens(width: int, height: int) -> int:
    """Tokens a high-detail image costs a vision model (OpenAI's tile rule: 85 + 170 per 512 px tile,
    after fitting 2048 px and then 768 px on the shorter side); an estimate for other servers."""
    scale = min(1.0, 2048 / max(width, height))
    w, h = width * scale, height * scale
    scale = min(1.0, 768 / min(w, h))
    w, h = w * scale, h * scale
    return 85 + 170 * int(np.ceil(w / 512) * np.ceil(h / 512))
