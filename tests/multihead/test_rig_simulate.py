"""One scene through every head: attitudes through the mountings, blinding by the Sun, the Earth
limb and the Moon, and the star lists' truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy.time import Time

from startrack.detect import StarDetector
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, random_rotations
from startrack.multihead._exclusion import BrightBodies, blinded_by, dawn_dusk_bodies, edge_angles_rad
from startrack.simulate import get_sensor_preset
from startrack.simulate._orbits import R_EARTH_KM
from startrack.simulate._rig import rig_star_lists, simulate_rig
from startrack.units import DEG

from .rigs import CAMERA, two_heads

SENSOR = get_sensor_preset("generic-cmos")


def bodies_with_sun_at(direction) -> BrightBodies:
    """The Sun in ``direction``, the Earth and the Moon in the opposite one (small)."""
    sun = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    return BrightBodies(sun, -sun, -sun, math.radians(0.27), math.radians(1.0), math.radians(0.26))


def test_each_head_sees_the_body_attitude_through_its_mounting_and_turns_with_the_body():
    rig = two_heads()
    body = random_rotations(None, 4)
    rate = np.radians([0.0, 0.0, 0.05])  # about body z: head a's roll, head b's cross-boresight axis
    frame = simulate_rig(rig, body, rate_body_rad_s=rate, sensor=SENSOR, max_mag=6.5, rng=1, epoch_jyear=2000.0)
    for head in rig:
        truth = frame.frames[head.name].truth
        assert (truth.rot_cam_from_icrs * head.rot_cam_from_icrs(body).inv()).magnitude() < 1e-12
        np.testing.assert_allclose(truth.rate_cam_rad_s, head.rot_cam_from_body.apply(rate), atol=1e-15)
        assert len(truth) > 5 and frame.blinded_by[head.name] == ""
    with pytest.raises(InvalidInputError, match="rate_body_rad_s"):
        simulate_rig(rig, body, rate_body_rad_s=[1.0, 2.0])


def test_a_head_facing_the_sun_is_blinded_and_detects_nothing():
    rig = two_heads()
    body = random_rotations(None, 6)
    sun_near_b = rig.head("b").rot_cam_from_icrs(body).inv().apply([0.0, 0.3, 1.0])  # 17 deg off b's boresight
    bodies = bodies_with_sun_at(sun_near_b)
    frame = simulate_rig(rig, body, sensor=SENSOR, max_mag=6.5, rng=2, bodies=bodies)
    assert frame.blinded_by == {"a": "", "b": "sun"}
    assert len(StarDetector().detect(frame.images["b"])) == 0
    assert len(StarDetector().detect(frame.images["a"])) > 5
    lists = rig_star_lists(rig, body, rng=3, bodies=bodies)
    assert len(lists["b"]) == 0 and lists["b"].blinded_by == "sun" and len(lists["a"]) > 5


def test_exclusion_geometry():
    bodies = bodies_with_sun_at([1.0, 0.0, 0.0])
    head = two_heads().head("a")  # exclusion 30 deg Sun, 20 deg Earth limb, 10 deg Moon
    near_sun = np.array([math.cos(29 * DEG), math.sin(29 * DEG), 0.0])
    far = np.array([0.0, 1.0, 0.0])
    assert blinded_by(head, bodies, near_sun) == "sun" and blinded_by(head, bodies, far) == ""
    edges = edge_angles_rad(bodies, far)
    assert edges["sun"] == pytest.approx(math.radians(90 - 0.27)) and edges["earth"] == pytest.approx(math.radians(89))
    leo = dawn_dusk_bodies("2025-03-20T12:00:00", 500.0)
    assert math.degrees(leo.earth_radius_rad) == pytest.approx(math.degrees(math.asin(R_EARTH_KM / (R_EARTH_KM + 500))))
    assert float(angle_between(leo.sun_icrs, leo.earth_icrs)) == pytest.approx(math.pi / 2, abs=1e-3)
    assert BrightBodies.at(Time("2025-03-20T12:00:00"), [R_EARTH_KM + 500.0, 0, 0]).earth_icrs[0] == pytest.approx(-1)
    with pytest.raises(InvalidInputError, match="ISO time"):
        dawn_dusk_bodies("noon")
    with pytest.raises(InvalidInputError, match="altitude"):
        dawn_dusk_bodies("2025-03-20T12:00:00", -5.0)


def test_star_lists_hold_the_true_positions_with_the_noise_asked_for():
    rig = two_heads()
    body = random_rotations(None, 9)
    lists = rig_star_lists(rig, body, rng=5, sigma_px=0.3, max_stars=1000, false_stars=2)
    for head in rig:
        s = lists[head.name]
        real = s.hip >= 0
        assert np.count_nonzero(~real) == 2 and np.all(np.isnan(s.true_x[~real]))
        d = np.concatenate([s.x[real] - s.true_x[real], s.y[real] - s.true_y[real]])
        assert np.std(d) == pytest.approx(0.3, rel=0.25)
        assert np.all(np.diff(s.flux) <= 0)
        assert CAMERA.in_image(s.true_x[real], s.true_y[real]).all()
