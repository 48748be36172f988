"""What the benchmark hands cedar-solve: its pixel convention, image size and FOV knowledge.

The runner (benchmarks/peers/cedar_runner.py) imports only numpy and the standard library, so it
is exercised here with a stand-in solver that records its inputs. Also checks that the scoring
turns tetra3-style RA / Dec / roll back into the attitude they came from.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from startrack.conventions import to_tetra3_yx
from startrack.frames import radec_roll_from_rotation, random_rotations
from startrack.units import ARCSEC

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"
sys.path.insert(0, str(BENCH))
sys.path.insert(0, str(BENCH / "peers"))

import cedar_runner  # noqa: E402
import methods  # noqa: E402
from methods import KNOWN_FOV_TOLERANCE, FovKnowledge  # noqa: E402

from startrack.analysis import _scoring as scoring  # noqa: E402
from startrack.analysis import _starlists as starlists  # noqa: E402


class RecordingSolver:
    def __init__(self):
        self.calls = []

    def solve_from_centroids(self, star_centroids, size, **kwargs):
        self.calls.append((np.asarray(star_centroids), size, kwargs))
        return {"status": 2}


def _fake_list(rng, n):
    return starlists.StarList(
        x=rng.uniform(0, 640, n), y=rng.uniform(0, 480, n),
        flux=np.sort(rng.uniform(1, 2, n))[::-1],
        is_real=np.ones(n, bool), hip=np.arange(n), rot_cam_from_icrs=random_rotations(rng=rng),
        sigma_px=0.1, missing_fraction=0.0, n_false=0, max_mag=6.0)


def _round_trip(tmp_path, knowledge):
    rng = np.random.default_rng(0)
    lists = [_fake_list(rng, 7), _fake_list(rng, 5)]
    est, err = knowledge.cedar_estimate()
    path = methods.save_for_peer(lists, tmp_path / "lists.npz", width=640, height=480,
                                   fov_estimate_deg=est, fov_max_error_deg=err)
    with np.load(path) as npz:
        data = {k: npz[k] for k in npz.files}
    solver = RecordingSolver()
    out = cedar_runner.solve_all(solver, data, timeout_ms=100.0, warmup=False)
    return lists, solver.calls, out


def test_runner_passes_tetra3_yx_half_pixel_centroids_and_height_width(tmp_path):
    lists, calls, out = _round_trip(tmp_path, FovKnowledge(fov_deg=12.0))
    for star_list, (yx, size, kwargs) in zip(lists, calls, strict=True):
        np.testing.assert_array_equal(yx, to_tetra3_yx(star_list.x, star_list.y))
        assert size == (480, 640)
        assert kwargs == {"fov_estimate": 12.0, "fov_max_error": 12.0 * KNOWN_FOV_TOLERANCE,
                          "solve_timeout": 100.0}
    assert not out["solved"].any() and np.all(np.isnan(out["ra_deg"]))


def test_runner_passes_a_fov_range_as_centre_and_half_width(tmp_path):
    _, calls, _ = _round_trip(tmp_path, FovKnowledge(fov_range_deg=(5.0, 35.0)))
    assert calls[0][2]["fov_estimate"] == 20.0 and calls[0][2]["fov_max_error"] == 15.0
    _, calls, _ = _round_trip(tmp_path, FovKnowledge())
    assert calls[0][2]["fov_estimate"] is None and calls[0][2]["fov_max_error"] is None


def test_radec_roll_in_degrees_give_back_the_attitude():
    truths = list(random_rotations(5, rng=1))
    ra, dec, roll = (np.degrees(a) for a in radec_roll_from_rotation(random_rotations(5, rng=1)))
    err = scoring.attitude_errors_rad(truths, scoring.rotations_from_radec_roll_deg(ra, dec, roll))
    assert np.all(err < 0.01 * ARCSEC)
    checks = scoring.boresight_and_roll_errors(truths, ra, dec, roll + 0.5)
    np.testing.assert_allclose(np.degrees(checks["roll_diff_rad"]), 0.5, atol=1e-9)
    assert np.all(checks["boresight_err_rad"] < 0.01 * ARCSEC)
