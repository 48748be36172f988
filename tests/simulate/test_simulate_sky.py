"""simulate_frame with the Hipparcos-2 catalog: known stars at known pixels, complete fields."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import get_preset
from startrack.frames import rotation_from_radec_roll
from startrack.simulate import SkyModel, random_attitude, simulate_frame
from startrack.units import DEG, PIXEL

try:
    from startrack.catalog import load_catalog
except ImportError:  # the catalog package is written in parallel
    pytest.skip("startrack.catalog.load_catalog is not available", allow_module_level=True)

BETELGEUSE, RIGEL, ARCTURUS = 27989, 24436, 69673
MAX_MAG = 6.0


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


@pytest.fixture(scope="module")
def camera():
    return get_preset("far-mst")


def catalog_vector(catalog, hip, epoch=None):
    return catalog.take(np.flatnonzero(catalog.hip == hip)).vectors(epoch)[0]


def test_orion_stars_land_where_the_camera_model_predicts(catalog, camera):
    # RA 83.8, Dec -5.4 (the Orion nebula); roll 90 deg puts the 30 deg axis north-south
    rot = rotation_from_radec_roll(83.8 * DEG, -5.4 * DEG, 90.0 * DEG)
    sim = simulate_frame(camera, rot, max_mag=MAX_MAG, noise=False)
    truth = sim.truth
    for hip in (BETELGEUSE, RIGEL):
        k = int(np.flatnonzero(truth.ids == hip)[0])
        x, y = camera.vector_to_pixel(rot.apply(catalog_vector(catalog, hip)))
        assert abs(truth.x[k] - x) < 1e-9 * PIXEL and abs(truth.y[k] - y) < 1e-9 * PIXEL
        assert truth.inside(margin_px=20)[k]
        patch = sim.image[round(y) - 3:round(y) + 4, round(x) - 3:round(x) + 4]
        assert sim.image[round(y), round(x)] == patch.max()  # the light is where the truth says
    assert set(truth.ids[:2]) == {BETELGEUSE, RIGEL}  # the two brightest stars of Orion


def independent_field(catalog, camera, rot):
    """HIP numbers, brightest first, of catalog stars <= MAX_MAG centred in the image (no cone)."""
    bright = catalog.brighter_than(MAX_MAG)
    x, y = camera.vector_to_pixel(rot.apply(bright.vectors()))
    inside = camera.in_image(x, y)
    order = np.argsort(bright.v_mag[inside], kind="stable")
    return bright.hip[inside][order]


@pytest.mark.parametrize("attitude", [
    rotation_from_radec_roll(83.8 * DEG, -5.4 * DEG, 0.0),
    rotation_from_radec_roll(10.0 * DEG, 88.5 * DEG, 40.0 * DEG),  # field contains the pole
    random_attitude(2024),
])
def test_truth_holds_exactly_the_catalog_stars_in_the_field(catalog, camera, attitude):
    sim = simulate_frame(camera, attitude, max_mag=MAX_MAG, noise=False)
    expected = independent_field(catalog, camera, attitude)
    inside_ids = sim.truth.ids[sim.truth.inside()]
    assert set(inside_ids) == set(expected)
    np.testing.assert_array_equal(inside_ids[:5], expected[:5])  # the brightest, in order
    assert np.all(np.diff(sim.truth.mag) >= 0)
    assert sim.truth.mag.max() <= MAX_MAG


def test_epoch_moves_high_proper_motion_stars(catalog, camera):
    rot = rotation_from_radec_roll(213.9 * DEG, 19.2 * DEG, 0.0)  # Arcturus, ~2.3 arcsec / yr
    at_1991 = simulate_frame(camera, rot, noise=False).truth
    at_2025 = simulate_frame(camera, rot, noise=False, epoch_jyear=2025.0).truth
    assert at_1991.epoch_jyear == pytest.approx(1991.25) and at_2025.epoch_jyear == 2025.0
    k1 = int(np.flatnonzero(at_1991.ids == ARCTURUS)[0])
    k2 = int(np.flatnonzero(at_2025.ids == ARCTURUS)[0])
    x, y = camera.vector_to_pixel(rot.apply(catalog_vector(catalog, ARCTURUS, 2025.0)))
    assert abs(at_2025.x[k2] - x) < 1e-9 * PIXEL and abs(at_2025.y[k2] - y) < 1e-9 * PIXEL
    moved = np.hypot(at_2025.x[k2] - at_1991.x[k1], at_2025.y[k2] - at_1991.y[k1])
    assert 0.5 * PIXEL < moved < 1.5 * PIXEL  # 34 yr * 2.3"/yr = 78" at 86.5"/px


def test_noisy_catalog_frame_and_a_custom_sky(catalog, camera):
    rot = random_attitude(7)
    sky = SkyModel.from_catalog(catalog, max_mag=4.0)
    a = simulate_frame(camera, rot, sky=sky, max_mag=3.0, rng=1)
    b = simulate_frame(camera, rot, sky=sky, max_mag=3.0, rng=1)
    assert a.image.dtype == np.uint16 and a.image.shape == (camera.height, camera.width)
    np.testing.assert_array_equal(a.image, b.image)
    assert a.truth.mag.max(initial=0.0) <= 3.0


def test_a_synthetic_sky_model_renders_its_own_stars(camera, vectors_at):
    rot = random_attitude(3)
    vectors = vectors_at(camera, rot, [100.0, 640.0, 1200.0], [80.0, 512.0, 1000.0])
    mags = np.array([2.0, 1.0, 7.0])
    sky = SkyModel(vectors, mags, np.array([5, 6, 7]), epoch_jyear=2030.0)
    sim = simulate_frame(camera, rot, sky=sky, max_mag=6.5, noise=False)
    np.testing.assert_array_equal(sim.truth.ids, [6, 5])  # the 7th-magnitude star is cut
    np.testing.assert_allclose(sim.truth.x, [640.0, 100.0], atol=1e-9)
    assert sim.truth.epoch_jyear == 2030.0
    assert mags.flags.writeable and not sky.mags.flags.writeable  # a read-only copy


def test_false_stars_join_the_sky_with_negative_ids(camera):
    sky = SkyModel.from_catalog(max_mag=4.0).with_false_stars(4000, rng=1, mag_range=(3.0, 3.5))
    assert np.sum(sky.ids < 0) == 4000 and np.all(sky.mags[sky.ids < 0] <= 3.5)
    sim = simulate_frame(camera, random_attitude(2), max_mag=4.0, sky=sky, noise=False)
    false = sim.truth.ids < 0
    assert 0 < false.sum() < 4000  # about 4000 x the field's share of the sky (~2 %)
    assert np.all(sim.truth.mag[false] >= 3.0)
