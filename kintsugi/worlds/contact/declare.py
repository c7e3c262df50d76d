"""A contact task's scene from what its config declares: every `ObjectSection`, `FixtureSection` and
`MarkerSection` of the task's own config becomes an object, a fixture or a goal disc of the trial.

A task file then needs no drawing code of its own: `declared_setup(cfg, drawer)` draws each section in
the order the config class lists them (sizes, masses and frictions as `physics` draws, positions as
`pose` draws, so the conditions pair trials as for every contact task) and names each draw
`<section>.<field>` in the trial record (`puck.diameter_m`, `puck.mass_kg`, `goal.x_m`).
"""

from __future__ import annotations

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import (SHAPE_SIZES, ContactConfig, FixtureSection, MarkerSection,
                                            ObjectSection)
from kintsugi.worlds.contact.objects import (Fixture, Geometry, Marker, Physics, Placement, board, box, capsule,
                                             cylinder, sphere)
from kintsugi.worlds.contact.spec import TrialSetup, nominal
from kintsugi.worlds.contact.world import Scene


def make_geometry(name: str, s: ObjectSection, sizes: tuple[float, ...]) -> Geometry:
    """An object's known model from its section and drawn sizes (see `SHAPE_SIZES`)."""
    return _shaped(name, s, sizes).model_copy(update={"colour": s.colour})


def _shaped(name: str, s: ObjectSection, sizes: tuple[float, ...]) -> Geometry:
    label, material = s.label or name.replace("_", " "), s.material
    if s.shape == "box":
        return box((sizes[0], sizes[1], sizes[2]), s.rgba, label, material)
    if s.shape == "cylinder":
        return cylinder(sizes[0], sizes[1], s.rgba, s.axis, label, material)
    if s.shape == "capsule":
        if sizes[1] < sizes[0]:
            raise ConfigError(f"{name}: a capsule's length {sizes[1]} m is shorter than its diameter {sizes[0]} m")
        return capsule(sizes[0], sizes[1], s.rgba, s.axis, label, material)
    if s.shape == "sphere":
        return sphere(sizes[0], s.rgba, label, material)
    if s.shape == "board":
        return board((sizes[0], sizes[1]), (sizes[2], sizes[3]), sizes[4], s.rgba, label, material)
    raise ConfigError(f"{name}: unknown shape {s.shape!r}; known: {', '.join(SHAPE_SIZES)}")


def draw_object(d: Drawer, name: str, s: ObjectSection) -> tuple[Geometry, Physics, Placement, Physics]:
    """(known model, true physics, start, nominal physics) of one declared object, drawn in a fixed order."""
    sizes = tuple(d.physics(f"{name}.{n}_m", r) for n, r in zip(SHAPE_SIZES[s.shape], s.size_m))
    truth = Physics(mass_kg=d.physics(f"{name}.mass_kg", s.mass_kg), friction=d.physics(f"{name}.friction", s.friction))
    place = Placement(x=d.pose(f"{name}.x_m", s.x_m), y=d.pose(f"{name}.y_m", s.y_m),
                      yaw_deg=d.pose(f"{name}.yaw_deg", s.yaw_deg))
    return make_geometry(name, s, sizes), truth, place, nominal(s.mass_kg, s.friction)


def draw_fixture(d: Drawer, name: str, s: FixtureSection) -> Fixture:
    half = tuple(x / 2 for x in s.size_m)
    return Fixture(half=half, pos=(d.pose(f"{name}.x_m", s.x_m), d.pose(f"{name}.y_m", s.y_m), half[2]),
                   rgba=s.rgba, label=s.label or name.replace("_", " "))


def draw_marker(d: Drawer, name: str, s: MarkerSection) -> Marker:
    return Marker(x=d.pose(f"{name}.x_m", s.x_m), y=d.pose(f"{name}.y_m", s.y_m), radius=s.radius_m, rgba=s.rgba,
                  label=s.label or name.replace("_", " "))


def declared_sections(cfg: ContactConfig) -> dict[str, ObjectSection | FixtureSection | MarkerSection]:
    """The task's own object, fixture and marker sections, in the config class's order."""
    out = {}
    for name in type(cfg).model_fields:
        section = getattr(cfg, name)
        if name not in ContactConfig.model_fields and isinstance(section, (ObjectSection, FixtureSection,
                                                                             MarkerSection)):
            out[name] = section
    return out


def declared_setup(cfg: ContactConfig, d: Drawer) -> TrialSetup:
    """One trial's scene, truth and nominal physics from the config's declared sections."""
    geometry, start, truth, nom, fixtures, markers = {}, {}, {}, {}, {}, {}
    for name, s in declared_sections(cfg).items():
        if isinstance(s, ObjectSection):
            geometry[name], truth[name], start[name], nom[name] = draw_object(d, name, s)
        elif isinstance(s, FixtureSection):
            fixtures[name] = draw_fixture(d, name, s)
        else:
            markers[name] = draw_marker(d, name, s)
    if not geometry:
        raise ConfigError(f"{type(cfg).__name__} declares no object (an ObjectSection field)")
    scene = Scene(geometry=geometry, start=start, fixtures=fixtures, markers=markers)
    return TrialSetup(scene=scene, truth=truth, nominal=nom, params=dict(d.drawn))
