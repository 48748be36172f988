"""The compiled batch look-up of four-star patterns: a catalog pattern seen by a camera is found."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.identify._database import (
    KEY_BINS,
    LEVEL_SHIFT,
    RATIO_SCALE,
    DatabaseSettings,
    _from_arrays,
    build_database_arrays,
)
from startrack.identify._quad_search import SearchSetup, focal_grid, search_batch, warm_up
from startrack.units import ARCSEC

SMALL = DatabaseSettings(fov_min_deg=20.0, fov_max_deg=30.0, max_mag=7.0)
SIZE_PX = 1024
FOCAL_PX = (SIZE_PX / 2) / math.tan(math.radians(10.0))  # 20 deg across
IMAGE_ORDER = np.array([2, 0, 3, 1])  # image star i is catalog star IMAGE_ORDER[i]


@pytest.fixture(scope="module")
def db():
    return _from_arrays(SMALL, build_database_arrays(SMALL))


def _seen(db, row: int, mirror: bool = False):
    """Normalised coordinates (u, w) of a database pattern's stars, in IMAGE_ORDER, and the attitude."""
    vec = db.vectors[db.pattern_stars[row].astype(np.int64)]
    centre = vec.mean(axis=0) / np.linalg.norm(vec.mean(axis=0))
    rot, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [centre])
    rot = Rotation.from_rotvec([0.0, 0.0, 0.7]) * rot  # some roll
    cam = rot.apply(vec[IMAGE_ORDER])
    u, w = cam[:, 0] / cam[:, 2], cam[:, 1] / cam[:, 2]
    return u, (-w if mirror else w), rot


def _setup(grid, focal_px, fit_focal):
    return SearchSetup(grid, focal_px, SIZE_PX, SIZE_PX, 0.5, 0.0015, 0.1, fit_focal)


def _row_in_level0(db, k: int) -> int:
    """The k-th of every 997th level-0 pattern whose smallest edge is a quarter of its largest or
    more (patterns of a tiny edge are too uncertain to be looked up at all)."""
    rows = np.arange(db.level_offsets[0], db.level_offsets[1])
    rows = rows[db.pattern_ratios[rows, 0] >= 0.25 * RATIO_SCALE]
    return int(rows[k * 997 % rows.size])


@pytest.mark.parametrize("k", [0, 1, 2])
def test_a_catalog_pattern_is_found_with_its_star_order_and_attitude(db, k):
    row = _row_in_level0(db, k)
    u, w, truth = _seen(db, row)
    fits = search_batch(db, u, w, np.array([[0, 1, 2, 3]]), _setup(focal_grid((1.0, 1.0), 0.0015), FOCAL_PX, False))
    hit = np.flatnonzero(fits.row == row)
    assert hit.size == 1
    i = hit[0]
    np.testing.assert_array_equal(IMAGE_ORDER[fits.image_stars[i]], [0, 1, 2, 3])
    error = (Rotation.from_quat(fits.quat[i]) * truth.inv()).magnitude()
    assert error < 1.0 * ARCSEC
    assert fits.focal[i] == pytest.approx(FOCAL_PX, rel=1e-12)


def test_a_free_focal_length_is_recovered_from_the_edges(db):
    row = _row_in_level0(db, 3)
    nominal = FOCAL_PX * 1.06  # the camera is believed 6 % longer than it is
    u, w, truth = _seen(db, row)
    u, w = u * FOCAL_PX / nominal, w * FOCAL_PX / nominal  # pixels measured, divided by the nominal focal length
    grid = focal_grid((nominal / (FOCAL_PX * 1.15), nominal / (FOCAL_PX * 0.85)), 0.0015)
    fits = search_batch(db, u, w, np.array([[0, 1, 2, 3]]), _setup(grid, nominal, True))
    i = np.flatnonzero(fits.row == row)[0]
    assert fits.focal[i] == pytest.approx(FOCAL_PX, rel=2e-3)
    assert (Rotation.from_quat(fits.quat[i]) * truth.inv()).magnitude() < 20.0 * ARCSEC


def test_a_mirrored_pattern_is_not_fitted(db):
    row = _row_in_level0(db, 4)
    u, w, _ = _seen(db, row, mirror=True)
    fits = search_batch(db, u, w, np.array([[0, 1, 2, 3]]), _setup(focal_grid((1.0, 1.0), 0.0015), FOCAL_PX, False))
    assert row not in fits.row
    assert fits.n_tried >= 1  # its edges matched: only the rotation fit tells the mirror apart


def test_a_batch_stops_at_each_pattern_that_yields_candidates_and_resumes_after_it(db):
    """Patterns: a mirrored one (no candidate), a real one, another mirrored one, another real one."""
    rows = [_row_in_level0(db, k) for k in (4, 0, 5, 1)]
    seen = [_seen(db, row, mirror=k in (0, 2)) for k, row in enumerate(rows)]
    u, w = np.concatenate([s[0] for s in seen]), np.concatenate([s[1] for s in seen])
    quads = np.arange(16).reshape(4, 4)
    setup = _setup(focal_grid((1.0, 1.0), 0.0015), FOCAL_PX, False)
    first = search_batch(db, u, w, quads, setup)
    assert first.next_pattern == 2 and rows[1] in first.row and first.n_tried >= 2  # the mirror's edges matched too
    second = search_batch(db, u, w, quads, setup, first.next_pattern)
    assert second.next_pattern == 4 and rows[3] in second.row and rows[1] not in second.row
    whole = [search_batch(db, u, w, quads[k:k + 1], setup) for k in range(4)]
    assert sorted(np.concatenate([first.row, second.row])) == sorted(np.concatenate([f.row for f in whole]))


def test_focal_grid_spans_the_range_with_one_point_for_a_known_focal_length():
    assert focal_grid((1.0, 1.0), 0.0015).tolist() == [1.0]
    grid = focal_grid((0.5, 3.5), 0.0015)
    assert grid[0] == pytest.approx(0.5) and grid[-1] == pytest.approx(3.5)
    assert np.all(np.diff(grid) > 0) and grid.size > 48


def test_cell_starts_bound_every_cell_of_the_key_index(db):
    n_cells = db.cell_starts.size - 1
    assert n_cells == db.level_fov_rad.size * KEY_BINS**2
    cells = np.random.default_rng(3).integers(0, n_cells, 200)
    for cell in cells:
        rows = slice(db.cell_starts[cell], db.cell_starts[cell + 1])
        prefix = ((cell // KEY_BINS**2) << LEVEL_SHIFT) + (cell % KEY_BINS**2) * 65536
        assert np.all((db.keys[rows] >= prefix) & (db.keys[rows] < prefix + 65536))
    assert np.all(np.diff(db.cell_starts) >= 0) and db.cell_starts[-1] == db.keys.size


def test_warm_up_compiles_the_signature_a_search_uses(db):
    from startrack.identify._quad_kernel import search

    warm_up(db)
    before = len(search.signatures)
    row = _row_in_level0(db, 5)
    u, w, _ = _seen(db, row)
    search_batch(db, u, w, np.array([[0, 1, 2, 3]]), _setup(focal_grid((0.9, 1.1), 0.0015), FOCAL_PX, True))
    assert len(search.signatures) == before  # no compilation inside a timed solve


def _ratios_at(u, w, scale):
    """The five sorted edge ratios of the four stars (u, w) seen at ``scale`` = f_nominal / f."""
    vec = np.column_stack([u * scale, w * scale, np.ones(4)])
    vec /= np.linalg.norm(vec, axis=1, keepdims=True)
    i, j = np.triu_indices(4, k=1)
    angles = np.sort(np.arccos(np.clip(np.sum(vec[i] * vec[j], axis=1), -1.0, 1.0)))
    return angles[:5] / angles[5]


@pytest.mark.parametrize("corner", [0.02, 0.17])
def test_trials_of_a_focal_range_each_span_about_one_focal_step(corner):
    """A pattern near the centre and one reaching the corner of a 20 deg field (5-35 deg range): the trials chosen
    from every eighth grid point cover the grid, and the ratios move by at most 1.25 focal steps
    within each trial's span (measured at every grid point)."""
    from startrack.identify._quad_kernel import _trial_starts

    step = 0.0015
    nominal = (SIZE_PX / 2) / math.tan(math.radians(10.0))
    lo, hi = (SIZE_PX / 2) / math.tan(math.radians(17.5)), (SIZE_PX / 2) / math.tan(math.radians(2.5))
    grid = focal_grid((nominal / hi, nominal / lo), step)
    u = np.array([corner, -0.8 * corner, 0.1 * corner, 0.5 * corner])
    w = np.array([0.2 * corner, corner, -0.9 * corner, 0.4 * corner])
    scratch = (np.empty((4, 3)), np.empty(6), np.empty(6), np.empty(5), np.empty(grid.size, np.int64))
    starts = _trial_starts(u, w, np.arange(4), grid, step, *scratch)
    assert starts[0] == 0 and np.all(np.diff(starts) > 0)
    ratios = np.array([_ratios_at(u, w, s) for s in grid])
    ends = np.append(starts[1:], grid.size)
    for first, end in zip(starts, ends, strict=True):
        moved = np.abs(np.diff(ratios[first:end], axis=0)).max(axis=1).sum() if end - first > 1 else 0.0
        assert moved <= 1.25 * step
    total = np.abs(np.diff(ratios, axis=0)).max(axis=1).sum()
    assert starts.size >= total / step * 0.8  # as many trials as the ratios need, roughly


def _sorted_edge_angles(px: np.ndarray) -> np.ndarray:
    """Sorted six edge angles (radians) of patterns (..., 4, 2) of pixel offsets from the centre."""
    v = np.concatenate([px / FOCAL_PX, np.ones(px.shape[:-1] + (1,))], axis=-1)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    i, j = np.triu_indices(4, 1)
    return np.sort(np.arccos(np.clip((v[..., i, :] * v[..., j, :]).sum(-1), -1.0, 1.0)), axis=-1)


def test_ratio_tolerances_cover_three_sigma_centroid_noise_without_waste():
    """Monte Carlo: 300 patterns x 200 draws of 0.5 px centroid noise. The tolerances must hold
    nearly every draw, and not be loose: the 99.9th-percentile error of the smallest ratio must
    reach half its tolerance in a typical pattern (the earlier bound, which used the small edge
    in place of the large one, reached 0.22)."""
    from startrack.identify._quad_kernel import ratio_tolerances

    rng = np.random.default_rng(5)
    sigma_px = 0.5
    patterns = rng.uniform(-350.0, 350.0, (300, 4, 2))
    clean = _sorted_edge_angles(patterns)
    noisy = _sorted_edge_angles(patterns[:, None] + rng.normal(0.0, sigma_px, (300, 200, 4, 2)))
    errors = np.abs(noisy[..., :5] / noisy[..., 5:] - (clean[:, :5] / clean[:, 5:])[:, None])
    tol = np.empty((300, 5))
    for p in range(300):
        ratio_tolerances(clean[p], clean[p, :5] / clean[p, 5], 0.0, 3.0 * sigma_px * math.sqrt(2.0), FOCAL_PX, 0.0,
                         tol[p])
    assert (errors > tol[:, None]).any(axis=-1).mean() < 0.005
    assert np.median(np.percentile(errors, 99.9, axis=1)[:, 0] / tol[:, 0]) > 0.5


def _ratios_of(ab: np.ndarray) -> np.ndarray:
    """Sorted edge ratios (..., 5) of patterns (..., 4, 2) given in pinhole coordinates (a, b)."""
    v = np.concatenate([ab, np.ones(ab.shape[:-1] + (1,))], axis=-1)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    i, j = np.triu_indices(4, 1)
    angles = np.sort(np.arccos(np.clip((v[..., i, :] * v[..., j, :]).sum(-1), -1.0, 1.0)), axis=-1)
    return angles[..., :5] / angles[..., 5:]


@pytest.mark.parametrize("fov_deg", [20.0, 60.0, 90.0])
def test_the_distortion_term_bounds_what_a_radial_lens_does_to_the_ratios(fov_deg):
    """Patterns anywhere in a square field, bent by r -> r (1 + k1 r^2) with |k1| <= 0.1: every
    ratio moves by less than ratio * shape_bound (the lens term of the look-up tolerance), and
    the bound is not idle (the worst pattern uses 40 % of it or more; 55-67 % measured)."""
    from startrack.identify._quad_kernel import radius2_range, shape_bound

    rng = np.random.default_rng(7)
    half = math.tan(math.radians(fov_deg / 2))
    ab = rng.uniform(-half, half, (2000, 4, 2))
    k1 = rng.uniform(-0.1, 0.1, (2000, 1, 1))
    bent = ab * (1.0 + k1 * (ab**2).sum(-1, keepdims=True))
    change = np.abs(_ratios_of(bent) - _ratios_of(ab))
    bound = np.array([shape_bound(0.1, *radius2_range(p[:, 0], p[:, 1], np.arange(4), 1.0)) for p in ab])
    used = change / (_ratios_of(ab) * bound[:, None])
    assert used.max() <= 1.0
    assert used.max() > 0.4


def test_an_edge_angle_has_its_least_value_over_a_scale_range_at_an_end():
    """What the skip of patterns too wide for every level rests on (:func:`._quad_kernel._wider_than`): the angle
    between two image stars, as the scale f_nominal / f grows, never dips inside a range of scales, so it exceeds a
    limit over the whole range when it does at both ends (random stars out to 70 deg off the axis)."""
    rng = np.random.default_rng(3)
    scales = np.geomspace(0.05, 3.0, 300)
    for _ in range(2000):
        a, b = rng.uniform(-3.0, 3.0, 2), rng.uniform(-3.0, 3.0, 2)
        va = np.column_stack([np.outer(scales, a), np.ones(scales.size)])
        vb = np.column_stack([np.outer(scales, b), np.ones(scales.size)])
        cos = np.sum(va * vb, axis=1) / np.linalg.norm(va, axis=1) / np.linalg.norm(vb, axis=1)
        i, j = np.sort(rng.integers(0, scales.size, 2))
        assert cos[i:j + 1].max() <= max(cos[i], cos[j]) + 1e-12


def test_a_pattern_too_wide_for_every_level_is_skipped_with_no_candidate(db):
    """A pattern whose largest edge exceeds the region diameter of every level the grid reaches yields nothing, as
    the level test of each trial would decide, and the search goes on to the next pattern."""
    from startrack.identify._quad_kernel import LARGEST_EDGE_SLACK, _wider_than

    row = _row_in_level0(db, 0)
    u, w, _ = _seen(db, row)
    wide_u, wide_w = np.append(u, 0.6), np.append(w, 0.6)  # a fifth star 43 deg off the axis
    grid = focal_grid((0.9, 1.1), 0.0015)
    limit = 2.0 * SMALL.region_fraction * db.level_fov_rad.max() / LARGEST_EDGE_SLACK
    vec = np.empty((4, 3))
    assert _wider_than(wide_u, wide_w, np.array([4, 1, 2, 3]), grid[0], grid[-1], math.cos(limit), vec, vec.copy())
    assert not _wider_than(u, w, np.array([0, 1, 2, 3]), grid[0], grid[-1], math.cos(limit), vec, vec.copy())
    fits = search_batch(db, wide_u, wide_w, np.array([[4, 1, 2, 3], [0, 1, 2, 3]]), _setup(grid, FOCAL_PX, True))
    assert fits.next_pattern == 2 and row in fits.row
