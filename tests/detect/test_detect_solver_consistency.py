"""Detections never contradict the solver: no star twice, and extended spots marked.

Issue 17: on two wide photographs ``solve_image`` raised "stars 359 and 1012 are at the same
position": a faint spot next to a bright star (a wing split off by the deblender, a fainter
companion) whose windowed centroid walked onto the bright star converged to its very fixed
point, and the detector reported the star twice. The frames below reproduce it: broad stars on
a black (clipped) sky with faint, narrower companions a few pixels away; before the merge of
coincident detections seeds 5, 10, 31 and 34 gave exactly coincident pairs (and most seeds
pairs closer than 0.01 px).

Extended spots: a nebula photo and a picture with an illustrated planet had 17 of their 20
brightest detections on nebula knots or glow. The frame below has 60 stars, 15 knots of
3.5-8 px standard deviation that outshine them, and a saturated disk with a glowing limb.
"""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Status
from startrack.detect import StarDetector, detect
from startrack.detect._merge import MERGE_RADIUS_PX
from startrack.identify import MatcherOptions
from startrack.solve import solve_stars
from startrack.units import PIXEL

SIZE = 400


def companion_frame(seed: int) -> np.ndarray:
    """40 broad stars (1-3 px) on a black sky, each with a fainter, narrower companion within
    7 px; 8-bit, clipped."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:SIZE, :SIZE]
    image = np.zeros((SIZE, SIZE))
    for _ in range(40):
        x0, y0 = rng.uniform(20, SIZE - 20, 2)
        s, amplitude = rng.uniform(1.0, 3.0), 10 ** rng.uniform(1.5, 4.0)
        image += amplitude * np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * s * s))
        dx, dy = rng.uniform(-7, 7, 2)
        image += amplitude * rng.uniform(0.02, 0.3) * np.exp(
            -((xx - x0 - dx) ** 2 + (yy - y0 - dy) ** 2) / (2 * (0.7 * s) ** 2))
    image = np.floor(image + rng.uniform(0, 1, image.shape) * 0.8)
    return np.clip(image, 0, 255).astype(np.uint8)


def _closest_pair_px(x: np.ndarray, y: np.ndarray) -> float:
    d = np.hypot(x[:, None] - x[None], y[:, None] - y[None])
    np.fill_diagonal(d, np.inf)
    return float(d.min())


@pytest.mark.parametrize("seed", [5, 10, 31, 34])
def test_no_two_detections_coincide(seed):
    det = detect(companion_frame(seed))
    assert len(det) >= 30
    assert _closest_pair_px(det.x, det.y) >= MERGE_RADIUS_PX * PIXEL


def test_merged_detection_keeps_the_light_of_both():
    """The merged detection carries the summed flux: the total over all detections is what the
    frame's spots hold, not less (nothing dropped) and not counted twice."""
    image = companion_frame(5)
    det = detect(image)
    keep_all = StarDetector(max_stars=None).detect(image)
    assert len(keep_all) == len(det)
    assert np.all(np.diff(det.flux) <= 0)  # still brightest first
    assert det.flux.sum() == pytest.approx(keep_all.flux.sum())


def test_large_frame_strips_report_a_boundary_star_once():
    """Strips (frames above max_block_px) overlap by 64 rows; a star on their boundary is kept
    once, and the strips give the single pass's stars."""
    image = np.vstack([companion_frame(10), companion_frame(31)])  # 800 x 400
    single = detect(image)
    strips = StarDetector(max_block_px=100_000).detect(image)  # strips of 192 rows
    assert _closest_pair_px(strips.x, strips.y) >= MERGE_RADIUS_PX * PIXEL
    d = np.hypot(single.x[:, None] - strips.x[None], single.y[:, None] - strips.y[None]).min(axis=1)
    assert np.mean(d < 0.25 * PIXEL) > 0.95  # each strip has its own background


def test_solver_accepts_the_detectors_output():
    """The star list the detector gives is one the solver takes (it raised before)."""
    det = detect(companion_frame(5))
    solution = solve_stars(det.x, det.y, width=SIZE, height=SIZE, flux=det.flux, fov_deg=15.0,
                           options=MatcherOptions(pattern_stars=5, timeout_s=1.0))
    assert isinstance(solution.status, Status)


def nebula_frame(seed: int, psf_px: float = 1.3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """60 stars, 15 bright knots (3.5-8 px sd) and a saturated disk of 40 px radius with a
    glowing limb, on a 100-ADU sky with 5 ADU noise; uint16. Returns the image and the star and
    knot positions (x, y), shape (60, 2) and (15, 2)."""
    rng = np.random.default_rng(seed)
    h, w = 600, 800
    yy, xx = np.mgrid[:h, :w]
    image = rng.normal(100, 5, (h, w))
    stars = np.column_stack([rng.uniform(10, w - 10, 60), rng.uniform(10, h - 10, 60)])
    stars = stars[np.hypot(stars[:, 0] - 650, stars[:, 1] - 450) > 90]
    for (x0, y0), f in zip(stars, 10 ** rng.uniform(2.5, 4.5, len(stars)), strict=True):
        image += f / (2 * np.pi * psf_px**2) * np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * psf_px**2))
    knots = np.column_stack([rng.uniform(20, 550, 15), rng.uniform(20, h - 20, 15)])
    for (x0, y0), s, f in zip(knots, rng.uniform(3.5, 8, 15), 10 ** rng.uniform(4, 5, 15), strict=True):
        image += f / (2 * np.pi * s * s) * np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * s * s))
    r = np.hypot(xx - 650, yy - 450)
    image += np.where(r < 40, 70000.0, 3000.0 * np.exp(-(r - 40) / 6.0))  # the planet and its limb
    return np.clip(image, 0, 65535).astype(np.uint16), stars, knots


def _nearest(points: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.hypot(points[:, 0, None] - x[None], points[:, 1, None] - y[None]).min(axis=0)


def test_nebula_knots_and_glow_are_not_point_sources():
    image, stars, knots = nebula_frame(1)
    det = detect(image)
    on_star = _nearest(stars, det.x, det.y) < 2 * PIXEL
    on_knot = _nearest(knots, det.x, det.y) < 4 * PIXEL
    on_planet = np.hypot(det.x - 650, det.y - 450) < 60
    assert det.point_quality is not None and det.point_quality.shape == (len(det),)
    assert on_star.sum() >= 50 and on_knot.sum() >= 12
    # among the 20 brightest most are knots or the planet ...
    assert (~on_star[:20]).sum() >= 8
    # ... and every one of those is marked, while nearly every star is a point source
    assert not np.any(det.is_point_source[on_knot | on_planet])
    assert np.mean(det.is_point_source[on_star]) >= 0.95
    # so the brightest point sources are stars
    points = np.flatnonzero(det.is_point_source)[:20]
    assert np.all(on_star[points])


def test_smeared_frame_stars_stay_point_sources():
    """The reference is the frame's own stars: when every star is elongated alike (smear), none
    is marked for it."""
    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[:400, :400]
    image = rng.normal(100, 5, (400, 400))
    for x0, y0, f in zip(rng.uniform(20, 380, 40), rng.uniform(20, 380, 40), 10 ** rng.uniform(3, 4.5, 40),
                         strict=True):
        image += f / (2 * np.pi * 3.0) * np.exp(-((xx - x0) ** 2 / (2 * 3.0**2) + (yy - y0) ** 2 / (2 * 1.0)))
    det = detect(image)
    assert len(det) >= 35
    assert np.mean(det.is_point_source) >= 0.95


def test_quality_of_a_star_list_is_unknown():
    """Detections built without the detector (a star list) count as point sources."""
    from startrack.results import Detections
    det = Detections(x=np.arange(3.0), y=np.arange(3.0), flux=np.ones(3), sigma_px=np.ones(3),
                     area_px=np.ones(3, dtype=np.int64), peak=np.ones(3), elongation=np.ones(3))
    assert det.point_quality is None and det.is_point_source.tolist() == [True] * 3
    assert det.take([0, 2]).point_quality is None
