"""The Pyramid matcher on the star-pair directory (Huffman 2006 §5.4-5.5)."""

import itertools
import math
import time

import numpy as np
import pytest

from startrack import Camera, Status, solve_stars
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error, random_rotations
from startrack.identify._pair_database import PairSettings, load_pair_database
from startrack.identify._pyramid import PyramidOptions, candidate_triangles, pyramid_triads
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC

CAMERA = Camera.from_fov(1024, 1024, 12.0)


def test_triads_are_every_combination_in_mortaris_order():
    triads = list(pyramid_triads(7))
    assert sorted(triads) == list(itertools.combinations(range(7), 3))
    assert triads[:3] == [(0, 1, 2), (1, 2, 3), (2, 3, 4)]  # stars change as fast as possible


def test_the_true_triangle_is_found_and_its_mirror_is_not():
    pdb = load_pair_database(PairSettings(fov_deg=math.ceil(CAMERA.fov_diagonal_deg)))
    rng = np.random.default_rng(3)
    for _ in range(5):
        tri = None
        while tri is None:
            a = rng.integers(len(pdb.vectors))
            near = np.flatnonzero(pdb.vectors @ pdb.vectors[a] > math.cos(math.radians(5)))
            if near.size >= 3:
                tri = np.array([a, *rng.choice(near[near != a], 2, replace=False)])
        rot = random_rotations(None, rng)
        image = rot.apply(pdb.vectors[tri])
        found = candidate_triangles(image, pdb, lambda angle: 1e-6)
        assert any(np.array_equal(t, tri) for t in found)
        mirrored = image * np.array([-1.0, 1.0, 1.0])
        assert not any(np.array_equal(t, tri) for t in candidate_triangles(mirrored, pdb, lambda angle: 1e-6))


def _star_list(seed):
    truth = random_rotations(None, rng=seed)
    sim = simulate_frame(CAMERA, truth, max_mag=7.0, sensor=get_sensor_preset("generic-cmos"), noise=False)
    inside = sim.truth.inside(margin_px=1.0)
    rng = np.random.default_rng(seed)
    x = sim.truth.x[inside] + rng.normal(0, 0.2, inside.sum())
    y = sim.truth.y[inside] + rng.normal(0, 0.2, inside.sum())
    return truth, np.clip(x, 0, 1023), np.clip(y, 0, 1023)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_pyramid_solves_with_a_camera_or_a_known_fov(seed):
    truth, x, y = _star_list(seed)
    for kwargs in ({"camera": CAMERA}, {"width": 1024, "height": 1024, "fov_deg": 12.1}):
        solution = solve_stars(x, y, method="pyramid", **kwargs)
        assert solution.solved, solution.reason
        assert attitude_error(truth, solution.rot_cam_from_icrs) < CAMERA.pixel_scale_arcsec * ARCSEC


def test_pyramid_refuses_mirrors_false_stars_and_unknown_fovs():
    _, x, y = _star_list(4)
    options = PyramidOptions(timeout_s=1.0)
    assert not solve_stars(1023 - x, y, camera=CAMERA, method="pyramid", options=options).solved
    rng = np.random.default_rng(5)
    fake = solve_stars(rng.uniform(0, 1023, 30), rng.uniform(0, 1023, 30), camera=CAMERA, method="pyramid",
                       options=options)
    assert fake.status in (Status.NO_MATCH, Status.TIMEOUT)
    with pytest.raises(InvalidInputError, match="within 5 %"):
        solve_stars(x, y, width=1024, height=1024, fov_range_deg=(5, 35), method="pyramid")
    with pytest.raises(InvalidInputError, match="method"):
        solve_stars(x, y, camera=CAMERA, method="triangles?")


def test_the_time_limit_holds_inside_a_triad_with_many_candidates(monkeypatch):
    """10,000 candidate triangles of 1 ms each for the first triad: the 0.2 s limit ends the
    search, not the end of the triad's candidates (10 s)."""
    from types import SimpleNamespace

    from startrack.identify import _pyramid as pyramid

    def many(vec, pdb, tolerance):
        return (np.array([0, 1, 2]) for _ in range(10_000))

    def slow_refusal(self, *args, **kwargs):
        time.sleep(0.001)

    monkeypatch.setattr(pyramid, "candidate_triangles", many)
    monkeypatch.setattr(pyramid.Confirmer, "confirm", slow_refusal)
    vectors = np.eye(3)
    pdb = SimpleNamespace(tree=None, vectors=vectors, catalog_rows=np.arange(3))
    x, y = np.array([100.0, 500.0, 900.0, 300.0]), np.array([100.0, 800.0, 200.0, 600.0])
    start = time.perf_counter()
    outcome = pyramid.match_pyramid(x, y, CAMERA, pdb, options=PyramidOptions(timeout_s=0.2))
    assert outcome.status is Status.TIMEOUT
    assert time.perf_counter() - start < 3.0  # s: the limit, not the triad's 10 s
