"""The compiled final fit and solution assembly against straightforward reference computations.

The attitude, residuals, covariance and RA / Dec / roll of a solve come from one compiled call
(:func:`startrack.identify._refine.solution_terms`), the re-match of the final fit from compiled
kernels (:func:`~startrack.identify._refine.match_predicted`, catalog stars chosen in a cone by
:func:`~startrack.identify._refine.stars_in_cone`). Each is compared here with the plain numpy /
scipy computation it replaces: ``Rotation.align_vectors``, :func:`startrack.frames.angle_between`,
:func:`startrack.attitude._covariance.covariance_batch`, :func:`startrack.frames.radec_roll_from_rotation`,
``Camera.vector_to_pixel`` with :func:`startrack.identify._verify.match_nearest`, and the per-star
KD-tree choice of catalog stars.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, Status, solve_stars
from startrack.analysis._starlists import Conditions, generate_star_lists, load_sky
from startrack.attitude._covariance import attitude_covariance, covariance_batch
from startrack.frames import angle_between, attitude_error, radec_roll_from_rotation, random_rotations
from startrack.identify import _final_fit as final_fit
from startrack.identify._candidate import Candidate
from startrack.identify._field_stars import field_stars
from startrack.identify._refine import match_predicted, pixel_vectors, solution_terms
from startrack.identify._verify import match_nearest
from startrack.units import ARCSEC

NOISE_RAD = 1e-12
"""Agreement expected of two float64 computations of the same angle (radians): rounding only."""

EASY = {"sigma_px_range": (0.1, 0.1), "missing_fraction_range": (0.0, 0.0), "false_stars_range": (0, 0),
        "mag_noise": 0.0, "max_stars": 25}


def _wrapped_diff(a, b):
    """a - b (radians) wrapped to [-pi, pi)."""
    return (np.asarray(a) - np.asarray(b) + np.pi) % (2 * np.pi) - np.pi


@pytest.mark.parametrize("n", [3, 7, 40])
def test_solution_terms_equal_the_reference_computations(n):
    rng = np.random.default_rng(n)
    for truth in random_rotations(5, rng):
        ref = rng.normal(size=(n, 3))
        ref /= np.linalg.norm(ref, axis=1, keepdims=True)
        obs = truth.apply(ref) + rng.normal(scale=1e-4, size=(n, 3))
        obs /= np.linalg.norm(obs, axis=1, keepdims=True)
        quat, matrix, residual, cov, (ra, dec, roll) = solution_terms(obs, ref, 2e-5)
        want, _ = Rotation.align_vectors(obs, ref)
        rot = Rotation.from_quat(quat)
        assert attitude_error(want, rot) < 1e-10  # rad: the same optimum (Davenport vs SVD)
        assert np.allclose(matrix, rot.as_matrix(), atol=1e-14)
        assert np.allclose(residual, angle_between(ref @ matrix.T, obs), rtol=0, atol=NOISE_RAD)
        assert np.allclose(cov, covariance_batch(obs[None], np.full((1, n), 2e-5))[0], rtol=1e-9, atol=0)
        want_ra, want_dec, want_roll = radec_roll_from_rotation(rot)
        assert abs(_wrapped_diff(ra, want_ra)) < NOISE_RAD and abs(dec - want_dec) < NOISE_RAD
        assert abs(_wrapped_diff(roll, want_roll)) < NOISE_RAD
        assert 0 <= ra < 2 * np.pi and 0 <= roll < 2 * np.pi


@pytest.mark.parametrize(("k1", "k2", "p1"), [(0.0, 0.0, 0.0), (0.01, 0.0, 0.0), (-0.3, 0.05, 1e-4), (-0.6, 0.0, 0.0)])
def test_pixel_vectors_equal_camera_pixel_to_vector(k1, k2, p1):
    """The compiled inversion of the lens model gives Camera.pixel_to_vector's vectors (the same
    iterations) and NaN at the same points (beyond the fold of a strong barrel lens)."""
    rng = np.random.default_rng(3)
    camera = Camera.from_fov(1024, 768, 60.0, cx=500.0).with_distortion(k1=k1, k2=k2, p1=p1)
    x, y = rng.uniform(-300, 1300, 400), rng.uniform(-300, 1100, 400)
    want, got = camera.pixel_to_vector(x, y), pixel_vectors(camera, x, y)
    assert np.array_equal(np.isnan(got), np.isnan(want))
    assert np.allclose(got, want, rtol=0, atol=NOISE_RAD, equal_nan=True)
    assert (k1 > -0.5) == bool(np.isfinite(want).all())  # the strong lens folds inside this range


def _reference_rematch(camera, vectors, matrix, x, y, radius_px):
    px, py = camera.vector_to_pixel(vectors @ matrix.T)
    inside = np.flatnonzero(camera.in_image(px, py))
    img_i, cat_i = match_nearest(x, y, px[inside], py[inside], radius_px)
    return img_i, inside[cat_i]


@pytest.mark.parametrize("k1", [0.0, -0.08, 0.05])
def test_match_predicted_equals_projection_and_match_nearest(k1):
    """Random catalog stars around the boresight (some behind the camera, some outside the
    image), image stars near some of them and clustered so that pairs compete."""
    rng = np.random.default_rng(11)
    camera = Camera.from_fov(800, 600, 25.0).with_distortion(k1=k1)
    matrix = random_rotations(1, rng)[0].as_matrix()
    for _ in range(5):
        cam_vec = np.column_stack([rng.uniform(-0.35, 0.35, (300, 2)), rng.choice([1.0, 1.0, 1.0, -1.0], 300)])
        vectors = cam_vec / np.linalg.norm(cam_vec, axis=1, keepdims=True) @ matrix  # ICRS
        px, py = camera.vector_to_pixel(vectors @ matrix.T)
        shown = np.flatnonzero(camera.in_image(px, py))[:40]
        x = np.concatenate([px[shown] + rng.normal(scale=1.5, size=shown.size), rng.uniform(0, 800, 10)])
        y = np.concatenate([py[shown] + rng.normal(scale=1.5, size=shown.size), rng.uniform(0, 600, 10)])
        got = match_predicted(vectors, matrix, camera, x, y, 3.0)
        want = _reference_rematch(camera, vectors, matrix, x, y, 3.0)
        assert want[0].size >= 20
        for g, w in zip(got, want, strict=True):
            assert np.array_equal(g, w)


def _easy_lists(fov_deg, n, seed=5):
    conditions = Conditions(fov_deg=fov_deg, **EASY)
    return conditions, generate_star_lists(conditions, n, seed, sky=load_sky(conditions))


@pytest.mark.parametrize("fov_deg", [10.0, 20.0, 30.0])
def test_cone_choice_rematches_as_the_per_star_choice(fov_deg):
    """The catalog stars chosen in one cone (and kept while the pose moves less than the margin)
    re-match exactly as those chosen near each image star, at the pose they serve."""
    conditions, lists = _easy_lists(fov_deg, 3)
    stars = field_stars(9.5, conditions.epoch_jyear)
    camera, rng = conditions.camera, np.random.default_rng(2)
    for image in lists:
        matrix = image.rot_cam_from_icrs.as_matrix()
        depth = final_fit.depth_limit(image.x.size, camera, len(stars.rows))
        field = final_fit._Field(image.x, image.y, stars, True, depth=depth)
        moved = Rotation.from_rotvec(rng.normal(size=3) * 2.0 / camera.fx).as_matrix() @ matrix
        cone = final_fit._Catalog.chosen(field, moved, camera)
        per_star = final_fit._Catalog.around_stars(field, moved, camera)
        assert cone.serves(matrix, camera) and cone.rows.size > per_star.rows.size
        got = final_fit.rematch(field, cone, matrix, camera)
        want = final_fit.rematch(field, per_star, matrix, camera)
        assert got[0].size >= 0.8 * image.x.size
        for g, w in zip(got, want, strict=True):
            assert np.array_equal(g, w)


@pytest.mark.parametrize(("fov_deg", "hint"), [(10.0, "known"), (20.0, "range"), (30.0, "range")])
def test_settled_fit_equals_the_numpy_path(fov_deg, hint, monkeypatch):
    """settle_matches with the compiled choice and re-match, and with the per-star KD-tree choice
    and numpy re-match (both limits set to zero): the same matches, attitude and camera."""
    conditions, lists = _easy_lists(fov_deg, 2, seed=8)
    kwargs = {"fov_deg": fov_deg} if hint == "known" else {"fov_range_deg": (5.0, 35.0)}
    for image in lists:
        sol = solve_stars(image.x, image.y, width=conditions.width, height=conditions.height,
                          epoch=conditions.epoch_jyear, **kwargs)
        assert sol.status is Status.OK
        first = sol.matches.det_index[:8]  # a candidate of eight right stars, at the solution's pose
        cand = Candidate(sol.rot_cam_from_icrs.as_matrix(), sol.camera, first, _rows(sol.matches.hip[:8]), 1e-9)
        stars = field_stars(9.5, conditions.epoch_jyear)
        focal = (0.97 * sol.camera.fx, 1.03 * sol.camera.fx)
        compiled = final_fit.settle_matches(image.x, image.y, stars, cand, focal)
        monkeypatch.setattr(final_fit, "CONE_SCAN_LIMIT", 0)
        monkeypatch.setattr(final_fit, "CONE_PAIRS_LIMIT", 0)
        plain = final_fit.settle_matches(image.x, image.y, stars, cand, focal)
        monkeypatch.undo()
        assert np.array_equal(compiled.image_index, plain.image_index)
        assert np.array_equal(compiled.catalog_rows, plain.catalog_rows)
        assert np.abs(compiled.matrix_cam_from_icrs - plain.matrix_cam_from_icrs).max() < 1e-12
        assert compiled.camera.fx == pytest.approx(plain.camera.fx, rel=1e-12)


def _rows(hip):
    from startrack.catalog import load_catalog

    order = np.argsort(load_catalog().hip)
    return order[np.searchsorted(load_catalog().hip[order], hip)]


@pytest.mark.parametrize(("fov_deg", "hint"), [(10.0, "known"), (20.0, "known"), (30.0, "range")])
def test_solution_equals_a_straightforward_fit_of_its_matches(fov_deg, hint):
    """A solve's attitude, residuals, covariance and RA / Dec / roll equal those computed with
    scipy and numpy from its own matches (observed directions through its camera)."""
    conditions, lists = _easy_lists(fov_deg, 3, seed=9)
    kwargs = {"fov_deg": fov_deg} if hint == "known" else {"fov_range_deg": (5.0, 35.0)}
    for image in lists:
        sol = solve_stars(image.x, image.y, width=conditions.width, height=conditions.height,
                          epoch=conditions.epoch_jyear, **kwargs)
        assert sol.status is Status.OK
        det, ref = sol.matches.det_index, sol.matches.cat_vectors
        observed = sol.camera.pixel_to_vector(image.x[det], image.y[det])
        want, _ = Rotation.align_vectors(observed, ref)
        assert attitude_error(want, sol.rot_cam_from_icrs) < 1e-10  # rad
        assert attitude_error(image.rot_cam_from_icrs, sol.rot_cam_from_icrs) < 2.0 / conditions.camera.fx  # 2 px
        assert np.allclose(sol.residuals_arcsec, angle_between(want.apply(ref), observed) / ARCSEC,
                           rtol=0, atol=1e-6)  # arcsec: the two optima differ by rounding
        unit = attitude_covariance(observed, 1.0)  # the covariance for sigma = 1 rad
        scale = sol.covariance_rad2[0, 0] / unit[0, 0]
        assert np.allclose(sol.covariance_rad2, scale * unit, rtol=1e-9, atol=0)
        sigma_px = np.sqrt(scale * sol.camera.fx * sol.camera.fy)
        assert 0.05 - 1e-9 <= sigma_px < 1.0  # the fit's RMS residual, at least 0.05 px
        ra, dec, roll = (np.degrees(v) for v in radec_roll_from_rotation(sol.rot_cam_from_icrs))
        assert (sol.ra_deg, sol.dec_deg, sol.roll_deg) == pytest.approx((ra, dec, roll), abs=1e-9)
