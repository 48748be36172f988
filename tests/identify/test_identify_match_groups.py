"""Van Bezooijen's match-group matcher (Jacobs 1995 §3, Jacobs 1995 Ch. 3 and App D)."""

import math

import numpy as np
import pytest

from startrack import Status
from startrack.camera import get_preset
from startrack.catalog import load_catalog
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, attitude_error, boresight, random_rotations
from startrack.identify._match_groups import (
    VanBezooijenOptions,
    iclim_start,
    largest_group,
    match_van_bezooijen,
    maximal_groups,
    mirror_ok,
    product_groups,
    region_mask,
    split_group,
    sub_catalogue,
    unique_groups,
)
from startrack.identify._pair_database import PairSettings, load_pair_database
from startrack.units import ARCSEC, PIXEL

CAMERA = get_preset("sunsat")  # Jacobs 1995's camera: 752 x 582 px, 11.2 x 8.3 deg
PDB = load_pair_database(PairSettings(fov_deg=14.0, stars_per_field=64, max_mag=6.0))  # every star to V 6
OPTIONS = VanBezooijenOptions(distance_tolerance_rad=150e-6, timeout_s=5.0)  # Jacobs 1995 Table 3-5 row 4
PIXEL_ANGLE = CAMERA.pixel_scale_arcsec * ARCSEC


def _star_list(seed, n_false=1, n_missing=1, sigma_px=0.2 * PIXEL, mag_sigma=0.2):
    """Brightest-first list of the guide stars in the field of a random attitude, with centroid
    noise, one of the 8 brightest missing and a false star third brightest. Returns the truth, x,
    y, magnitudes and HIP per entry (-1 for false stars)."""
    rng = np.random.default_rng(seed)
    v_mag = load_catalog().v_mag[PDB.catalog_rows]
    while True:
        truth = random_rotations(rng=rng)
        cam_vec = truth.apply(PDB.vectors)
        idx = np.flatnonzero(cam_vec[:, 2] > 0.9)
        x, y = CAMERA.vector_to_pixel(cam_vec[idx])
        inside = CAMERA.in_image(x, y, margin_px=2.0)
        if inside.sum() >= 10:
            break
    idx, x, y = idx[inside], x[inside], y[inside]
    order = np.argsort(v_mag[idx])
    keep = np.delete(order, rng.choice(8, n_missing, replace=False))
    hip = load_catalog().hip[PDB.catalog_rows[idx[keep]]].astype(np.int64)
    x = x[keep] + rng.normal(0, sigma_px, keep.size)
    y = y[keep] + rng.normal(0, sigma_px, keep.size)
    mags = v_mag[idx[keep]] + rng.normal(0, mag_sigma, keep.size)
    for _ in range(n_false):
        at = 2
        x, y = np.insert(x, at, rng.uniform(0, 751)), np.insert(y, at, rng.uniform(0, 581))
        mags, hip = np.insert(mags, at, mags[at]), np.insert(hip, at, -1)
    return truth, x, y, mags, hip


def _check_identified(outcome, truth, hip):
    assert outcome.status is Status.OK, outcome.reason
    cand = outcome.candidate
    assert cand.image_index.size >= 6
    assert not np.any(hip[cand.image_index] == -1)  # the false star stays unmatched
    np.testing.assert_array_equal(load_catalog().hip[cand.catalog_rows], hip[cand.image_index])
    assert attitude_error(truth, cand.rot_cam_from_icrs) < 3 * PIXEL_ANGLE  # roll is the weak axis
    pointing = angle_between(boresight(truth), boresight(cand.rot_cam_from_icrs))
    assert pointing < 0.5 * PIXEL_ANGLE


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_identifies_a_list_with_a_missing_and_a_false_star(seed):
    truth, x, y, _, hip = _star_list(seed)
    _check_identified(match_van_bezooijen(x, y, CAMERA, PDB, options=OPTIONS), truth, hip)


def test_magnitudes_narrow_the_pair_matches_and_still_identify():
    truth, x, y, mags, hip = _star_list(5)
    outcome = match_van_bezooijen(x, y, CAMERA, PDB, options=OPTIONS, magnitudes=mags)
    _check_identified(outcome, truth, hip)
    with pytest.raises(InvalidInputError, match="magnitudes"):
        match_van_bezooijen(x, y, CAMERA, PDB, options=OPTIONS, magnitudes=mags[:-1])


def test_a_sub_catalogue_around_the_attitude_identifies_too():
    truth, x, y, _, hip = _star_list(6)
    sub = sub_catalogue(PDB, region_mask(PDB, boresight(truth)[None], math.radians(15.0)))
    assert 0 < len(sub.vectors) < len(PDB.vectors) / 20
    keys = {tuple(sorted(p)) for p in sub.catalog_rows[sub.pairs].tolist()}
    assert keys <= {tuple(sorted(p)) for p in PDB.catalog_rows[PDB.pairs].tolist()}
    np.testing.assert_allclose(sub.angles, angle_between(sub.vectors[sub.pairs[:, 0]], sub.vectors[sub.pairs[:, 1]]))
    _check_identified(match_van_bezooijen(x, y, CAMERA, sub, options=OPTIONS), truth, hip)


def test_mirrored_and_false_star_lists_are_refused():
    _, x, y, _, _ = _star_list(7, n_false=0)
    mirrored = match_van_bezooijen(CAMERA.width - 1 - x, y, CAMERA, PDB, options=OPTIONS)
    assert mirrored.status is Status.NO_MATCH and mirrored.candidate is None
    rng = np.random.default_rng(8)
    for _ in range(3):
        fake = match_van_bezooijen(rng.uniform(0, 751, 12), rng.uniform(0, 581, 12), CAMERA, PDB, options=OPTIONS)
        assert fake.status in (Status.NO_MATCH, Status.TIMEOUT) and fake.candidate is None
    assert match_van_bezooijen(x[:2], y[:2], CAMERA, PDB).status is Status.TOO_FEW_STARS


def test_group_generation_is_the_cartesian_product_of_table_d3():
    # kernel (o1, g5): o2 in {g12, g33}, o3 in {g15, g40}, o4 none, o5 in {g22, g54, g56}
    groups = product_groups([["o2g12", "o2g33"], ["o3g15", "o3g40"], [], ["o5g22", "o5g54", "o5g56"]])
    assert len(groups) == 12 and len(set(groups)) == 12
    assert all(g[0][:2] == "o2" and g[1][:2] == "o3" and g[2][:2] == "o5" for g in groups)


def test_geometry_test_splits_the_group_of_table_3_4():
    fits = {(2, 4), (2, 8), (4, 8), (4, 6), (6, 22)} | {(1, k) for k in (2, 4, 6, 8, 22)}

    def consistent(a, b):
        return (min(a, b), max(a, b)) in fits

    split = split_group([1, 2, 4, 6, 8, 22], consistent)
    maximal = {g for g in split if not any(g < h for h in split)}
    assert maximal == {frozenset({1, 2, 4, 8}), frozenset({1, 4, 6}), frozenset({1, 6, 22})}
    members = [2, 4, 6, 8, 22]
    adjacency = np.array([[a != b and consistent(a, b) for b in members] for a in members])
    assert {frozenset(members[i] for i in g) | {1} for g in maximal_groups(adjacency)} == maximal


def test_maximal_groups_equal_product_then_split_on_random_graphs():
    rng = np.random.default_rng(9)
    for _ in range(20):
        star = rng.integers(0, 5, 12)  # observed star of each associated match
        adjacency = (rng.random((12, 12)) < 0.6) & (star[:, None] != star[None])
        adjacency = np.triu(adjacency, 1) | np.triu(adjacency, 1).T
        split = set()
        for group in product_groups([np.flatnonzero(star == s).tolist() for s in range(5)]):
            split.update(split_group(group, lambda a, b, adj=adjacency: adj[a, b]))
        maximal = {g for g in split if not any(g < h for h in split)}
        assert {frozenset(g) for g in maximal_groups(adjacency)} == maximal


def test_mirror_test_refuses_a_reflected_constellation():
    rng = np.random.default_rng(10)
    guide = PDB.vectors[np.argsort(PDB.vectors @ PDB.vectors[100])[-5:]]
    observed = random_rotations(rng=rng).apply(guide)
    assert mirror_ok(observed, guide)
    assert not mirror_ok(observed * np.array([-1.0, 1.0, 1.0]), guide)
    assert mirror_ok(observed[:2] * np.array([-1.0, 1.0, 1.0]), guide[:2])  # two stars: untestable


def test_redundancy_elimination_iclim_and_largest_group():
    a, b, c = frozenset({1, 2, 3}), frozenset({3, 2, 1}), frozenset({1, 2, 4})
    assert unique_groups([a, b, c, a]) == [a, c]
    assert iclim_start([7] * 8 + [2] * 50) == 6
    assert iclim_start([1, 1]) == 0
    d, e = frozenset({5, 6, 7}), frozenset({1, 8, 9})
    quality = {a: 2.0, c: 1.0, d: 0.5, e: 3.0}
    assert largest_group([a, c], quality.get) == c  # sharing two matches: the better one
    assert largest_group([a, e], quality.get) == a  # sharing one: the better one, to be confirmed
    assert largest_group([a, d], quality.get) is None  # sharing none: ambiguous
    assert largest_group([a, frozenset({9, 8})], quality.get) == a
    assert largest_group([], quality.get) is None


def test_invalid_options_raise():
    with pytest.raises(InvalidInputError, match="stars"):
        VanBezooijenOptions(stars=2)
    with pytest.raises(InvalidInputError, match="distance_tolerance_rad"):
        VanBezooijenOptions(distance_tolerance_rad=-1.0)
