"""What coral's roles are shown of the scene: each object's label and known sizes, and the camera's image."""

from __future__ import annotations

from typing import Any


def object_label(known: Any, name: str) -> str:
    """What a user or a camera calls an object: its known model's label, or its name when it has none or when
    another object has the same label (every object must be told apart)."""
    labels = [g.label or n for n, g in known.geometry.items()]
    label = known.geometry[name].label or name
    return label if labels.count(label) == 1 else name


def object_views(known: Any) -> list[Any]:
    """What the priors role is told of each object: its label, the size of its known model's main part, and
    every part's size and place (a board's plate and handle)."""
    from kintsugi.methods.coral.types import ObjectView, PartView

    return [ObjectView(label=object_label(known, n), size_m=tuple(2 * h for h in g.parts[0].half),
                       parts=[PartView(size_m=tuple(2 * h for h in p.half), offset_m=p.pos) for p in g.parts])
            for n, g in known.geometry.items()]


def scene_png(robot: Any, reasoner: Any) -> bytes | None:
    """The scene camera's image for a request, when the backend looks at images (a model endpoint does; the
    embedded rules read labels and sizes)."""
    from kintsugi.reasoning.base import sees_images

    if not sees_images(reasoner):
        return None
    from kintsugi.methods.recovery.method import to_png

    return to_png(robot.camera_image())
