"""The variables cost code reads in the control loop: the fast bounding box and contact distance equal the
per-corner rotations and Attractor.distance they replace, and a measured state provides every variable the
formulation request lists (so code probed on the listed vocabulary runs in the loop)."""

from __future__ import annotations

import numpy as np

from kintsugi.methods.coral.env import _bounds, contact_distance, entry_env, first_env, state_env, static_env
from kintsugi.methods.mppi.costs import Attractor, ContactRegion, norm
from kintsugi.worlds.contact.objects import board
from kintsugi.worlds.contact.spec import corners
from kintsugi.worlds.contact.world import rotate

from tests.coral_fixtures import coral_scene


def _poses(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(6, 4, 4))
    return rng.normal(size=(6, 4, 3)), q / np.linalg.norm(q, axis=-1, keepdims=True)


def test_bounds_equal_the_rotated_corners_of_a_two_part_board() -> None:
    geo = board((0.2, 0.16), (0.1, 0.05), 0.02, (1, 1, 1, 1))
    pos, quat = _poses(0)
    c = corners(geo)
    world = pos[..., None, :] + rotate(np.broadcast_to(quat[..., None, :], (6, 4, len(c), 4)),
                                       np.broadcast_to(c, (6, 4, *c.shape)))
    lo, hi = _bounds(geo, pos, quat)
    assert np.allclose(lo, world.min(-2), atol=1e-12) and np.allclose(hi, world.max(-2), atol=1e-12)


def test_contact_distance_equals_the_attractor() -> None:
    a = Attractor(ContactRegion(obj="box", center=(-0.03, 0, -0.01), normal=(-1, 0, 0), radius=0.008, standoff=0.01,
                                drop=0.006), 8, seed=0)
    pos, quat = _poses(1)
    tcp = np.random.default_rng(2).normal(size=(6, 4, 3))
    world = pos[:, :, None, :] + rotate(np.broadcast_to(quat[:, :, None, :], (6, 4, 8, 4)), a.targets[None, None])
    assert np.allclose(contact_distance(a, tcp, pos, quat), norm(tcp[:, :, None, :] - world).min(-1), atol=1e-12)


def test_a_measured_state_provides_every_listed_variable() -> None:
    from kintsugi.methods.coral.formulate import request_variables

    ctx, cfg, obs, req, world = coral_scene("push-force", 0)
    a = Attractor(ContactRegion(obj="box", center=(-0.03, 0, 0), normal=(-1, 0, 0), radius=0.01), 4)
    env = state_env(obs, ctx.known, {**static_env(ctx.known, cfg), **entry_env(obs, ctx.known), **first_env(obs),
                                       "kept": 0.0}, a, 0.1)
    assert request_variables(req) <= set(env)
    assert np.isclose(env["box_lo"][0], env["box_pos"][0] - env["box_half"][0], atol=0.01)  # yaw is small
    world.close()
