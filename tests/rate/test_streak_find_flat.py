"""The streak search on a frame without noise (rate._streak_find): a constant frame, or a noise-free
one mostly at its background, has no threshold to set and gives no candidate (it raised "image has
no noise to set a threshold by", which made a blank frame an error of the Tracker, of
solve_streaked and of track_streaks rather than TOO_FEW_STARS); noisy frames are searched as before."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, Status
from startrack.errors import InvalidInputError
from startrack.rate import find_streak_candidates, solve_streaked, track_streaks
from startrack.rate._streak_find import ROUNDING_SIGMA, robust_level
from startrack.units import DEG

CAMERA = Camera.from_fov(256, 256, 12.0)


def _noise_free_frame() -> np.ndarray:
    """A background of 100 counts and two bright horizontal streaks, no noise."""
    image = np.full((256, 256), 100, dtype=np.uint16)
    image[60:63, 40:120] += 500
    image[180:183, 100:200] += 800
    return image


def _noisy_frame() -> np.ndarray:
    """The same streaks over Gaussian noise of 5 counts."""
    noise = np.random.default_rng(3).normal(0.0, 5.0, (256, 256))
    return _noise_free_frame().astype(np.float64) + noise


@pytest.mark.parametrize("image", [np.full((256, 256), 100, np.uint16), np.zeros((256, 256)), _noise_free_frame()],
                         ids=["constant", "zeros", "noise-free"])
def test_a_frame_without_noise_has_no_candidate(image):
    found = find_streak_candidates(image)
    assert len(found) == 0 and found.labels.shape == (64, 64) and not found.labels.any()
    assert found.background == float(np.median(image[::8, ::8]))
    assert found.noise == ROUNDING_SIGMA == robust_level(image)[1]  # counts: the rounding floor, not 0


def test_non_finite_pixels_are_still_refused():
    image = np.full((256, 256), np.nan)
    with pytest.raises(InvalidInputError, match=r"^image has no finite pixel value"):  # a few are filled
        find_streak_candidates(image)
    assert np.isnan(robust_level(image)[1])  # not raised to the rounding floor


def test_a_noisy_frame_is_searched_as_before():
    image = _noisy_frame()
    found = find_streak_candidates(image)
    sample = image[::8, ::8]
    assert found.noise == pytest.approx(1.4826 * np.median(np.abs(sample - np.median(sample))), rel=1e-12)
    assert found.noise == pytest.approx(5.0, rel=0.15)  # counts: the noise drawn
    assert len(found) == 2
    centres = found.centroid_xy[np.argsort(found.centroid_xy[:, 1])]
    np.testing.assert_allclose(centres, [[79.5, 61.0], [149.5, 181.0]], atol=2.0)  # px: the streaks' middles
    np.testing.assert_allclose(np.sort(found.length_px), [80.0, 100.0], rtol=0.15)  # px: their lengths


def test_the_streak_solvers_call_a_blank_frame_too_few_stars():
    blank = np.full((256, 256), 100, dtype=np.uint16)
    assert solve_streaked(blank, camera=CAMERA, exposure_s=0.1).status is Status.TOO_FEW_STARS
    omega = np.array([5.0, 0.0, 0.0]) * DEG
    tracked = track_streaks(blank, CAMERA, Rotation.random(random_state=2), omega, 0.1, epoch_jyear=2000.0,
                            slack_px=10.0)
    assert tracked.status is Status.TOO_FEW_STARS
