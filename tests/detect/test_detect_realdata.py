"""The default detector on real sky images against astrometry.net's matched stars.

Images and truth: ``../shared/realdata`` (its README.md); the reference stars and the scoring are
``benchmarks/detect_realdata.py``'s: astrometry.net's genuine matches (the ``.corr`` rows whose
image star lies within 2 px of the catalogue star's own position: two rows of roof.jpg, 6 and
10 px off, and one of orion_trees.jpg and tree.jpg are chance coincidences), found when a
detection lies within 2 px; a detection is *unconfirmed* when it is near neither a match nor a
Hipparcos star (astrometry.net's WCS).

Goal (issue 17): at least 90 % of the matched stars on every image, with no more false
detections than before. The openstartracker frames are scored with the Huffman 2006 §4.1 median
dark built from the three frames (their own ``median_image.png`` is truncated), the camera's
fixed pattern. Measured (benchmark), before issue 17 -> now: img3 12 -> 12 of 12, img4 11 -> 11
of 12, img6 15 -> 15 of 16 (with the dark; 12 -> 15 without), crappy 11 -> 11 of 12, orion_trees
19 -> 26 of 26, roof 27 -> 27 of 33, tree 15 -> 19 of 24, pleiades 26 -> 27 of 30. Where the goal
is not met the strict xfail says why (it turns into a failure, asking for the mark to go, the day
it passes):

* img6 with the dark reaches it (15 of 16) once the pipeline keeps the fine pass's spots by
  their own clutter (``fine_pass.quiet_surroundings``, ``LOCAL_THRESHOLD`` below; 14 of 16
  before): its two misses had raw rings 1.75 times the pixel noise, over the fine pass's 1.4,
  busy only through the rounding of 8-bit pixels whose noise is half a count (open sky's raw
  rings spread 1.36 times the pixel noise here), quiet in the fine image (1.05 and 0.97); the
  brighter (10.6 sigma) stands 1.5 times the threshold above its ring there, the fainter (7.1)
  does not and stays missed;
* roof: three on the border (one with no spot, two merged with the border's bright band), one
  beside a bright stripe (12.7 sigma in the fine image, a quiet ring, but 1.8 in the binned one
  and a tile of 7 times the sky's clutter; the fine pass does not run, the stars being 1.44 px),
  one 6 px from a brighter star at 3.3 sigma, one at 4.7 sigma;
* tree: four at 2.5-6.0 sigma of the fine image, where 116-635 unconfirmed peaks of the frame
  are as significant (for 22 of 24, a threshold of 3.6-4.4 sigma in any of six full-resolution
  filters measured, with 190-300 unconfirmed peaks above it), and one inside the tree. A sixth,
  blended, was lost (its centroid 2.31 px off) while the clutter ratio measured on the residual
  let an unconfirmed spot near the right border pass and the frame's PSF width estimate went
  from 2.25 to 2.49 px; since the spots that are not point sources (lit leaves) are left out of
  that estimate, it is 1.53 px, the star is found again, and the median offset from
  astrometry.net fell from 0.20 to 0.09 px. One more unconfirmed spot now ranks above the
  30th, so 9 of the found stars are among our brightest 30, not 10.

``test_every_miss_has_a_cause`` pins these causes (``benchmarks/detect_realdata.py --misses``):
a significant, isolated star on open sky dropped by a filter would fail it.

Unconfirmed detections: no more among our brightest 50 (what a matcher uses) than before, but
on tree.jpg (19 against 18, a strict xfail), and a ceiling on all of them. orion_trees has 14
in all (3 before): the full-resolution pass finds faint compact spots 3-13 px from the nearest
Hipparcos star, below Hipparcos's completeness in that Milky Way field (most look like stars
in a cut-out); they rank below 50.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from detect_realdata import (  # noqa: E402
    IMAGES,
    OPENSTARTRACKER,
    TOP_N,
    load_image,
    misses,
    openstartracker_dark,
    reference,
    score,
    significance_maps,
)

from startrack.detect import StarDetector  # noqa: E402
from startrack.detect import _pipeline as pipeline
from startrack.detect._fine_pass import MAX_RING_NOISE, fine_regions, quiet_surroundings, ring_noise_ratio  # noqa: E402
from startrack.units import PIXEL  # noqa: E402

GOAL = 0.90
TOP_CHECKED = 50

# image: (found now, found in our top 30 now, unconfirmed among the top 50 before issue 17,
#         unconfirmed in all now, reaches the 90 % goal)
EXPECTED = {
    "img3.png": (12, 12, 38, 78, True),
    "img4.png": (11, 11, 39, 71, True),
    "img6.png": (14, 14, 36, 77, False),
    "crappy.jpg": (11, 11, 2, 3, True),
    "orion_trees.jpg": (26, 18, 3, 14, True),
    "roof.jpg": (27, 24, 1, 1, False),
    "tree.jpg": (19, 9, 18, 21, False),
    "pleiades.jpg": (27, 18, 4, 4, True),
}
# the pipeline keeping the fine pass's spots by their own clutter (fine_pass.quiet_surroundings):
# img6's star at (809, 102), in a ring busy only through rounding, is found
LOCAL_THRESHOLD = hasattr(pipeline, "quiet_surroundings")
if LOCAL_THRESHOLD:
    EXPECTED["img6.png"] = (15, 14, 36, 77, True)
MORE_FALSE = {"tree.jpg": "19 unconfirmed among the brightest 50 against 18: a clump of lit leaves split in two"}


@pytest.fixture(scope="module")
def detectors(realdata_dir) -> dict:
    """Per image, the scored detector: the default, with the median dark for the openstartracker frames."""
    dark = openstartracker_dark()
    return {name: StarDetector(dark_frame=dark) if folder == OPENSTARTRACKER else StarDetector()
            for name, folder in IMAGES.items()}


@pytest.fixture(scope="module")
def results(detectors) -> dict:
    """Per image: the scored detector's detections and the reference stars."""
    return {name: (detector.detect(load_image(name)), reference(name)) for name, detector in detectors.items()}


@pytest.mark.parametrize("name", list(IMAGES))
def test_matched_stars_are_found(results, name):
    det, ref = results[name]
    s = score(det.x, det.y, ref, det.is_point_source)
    found_now, top_now, *_ = EXPECTED[name]
    assert s.found >= found_now, f"{name}: {s.found}/{s.matched} found (regression floor {found_now})"
    assert s.top >= top_now, f"{name}: {s.top} in our top {TOP_N} (regression floor {top_now})"
    assert s.median_px < 0.3 * PIXEL  # astrometry.net's positions are good to a few tenths of a pixel
    assert s.point_sources >= s.found - 2  # the stars are point sources


@pytest.mark.parametrize("name", [
    pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=MORE_FALSE[name]) if name in MORE_FALSE else ())
    for name in IMAGES
])
def test_no_more_false_detections(results, name):
    det, ref = results[name]
    _, _, before_top, now_all, _ = EXPECTED[name]
    assert score(det.x, det.y, ref).unconfirmed <= now_all  # a regression ceiling
    assert score(det.x[:TOP_CHECKED], det.y[:TOP_CHECKED], ref).unconfirmed <= before_top


@pytest.mark.parametrize("name", [
    pytest.param(name, marks=() if meets else pytest.mark.xfail(strict=True, reason="below the goal: module docstring"))
    for name, (*_, meets) in EXPECTED.items()
])
def test_ninety_percent_goal(results, name):
    det, ref = results[name]
    s = score(det.x, det.y, ref)
    assert s.recall >= GOAL, f"{name}: {s.found}/{s.matched} found"


@pytest.mark.parametrize("name", [n for n, folder in IMAGES.items() if folder == OPENSTARTRACKER])
def test_low_signal_frames_without_the_dark(realdata_dir, truth_table, name):
    """Without the dark the frames' hot pixels stay, yet we find at least the stars
    astrometry.net itself counted (``n_match``) and keep fewer unconfirmed spots than the
    detector before issue 17 (35, 37 and 33 of its 47)."""
    ref = reference(name)
    det = StarDetector().detect(load_image(name))
    s = score(det.x, det.y, ref)
    n_match = int(next(row["n_match"] for row in truth_table if row["file"] == name))
    assert s.found >= n_match
    assert s.unconfirmed <= {"img3.png": 35, "img4.png": 37, "img6.png": 33}[name]
    assert s.median_px < 0.3 * PIXEL


def test_extended_spots_of_the_tree_are_marked(results):
    """tree.jpg: most unconfirmed detections are lit leaves, and the point-source quality
    marks them while it keeps the stars."""
    det, ref = results["tree.jpg"]
    d = np.hypot(ref.x[:, None] - det.x[None], ref.y[:, None] - det.y[None]).min(axis=0)
    dh = np.hypot(ref.hip_x[:, None] - det.x[None], ref.hip_y[:, None] - det.y[None]).min(axis=0)
    unconfirmed = (d >= 2 * PIXEL) & (dh >= 2 * PIXEL)
    assert np.mean(~det.is_point_source[unconfirmed]) >= 0.5
    assert np.all(det.is_point_source[d < 2 * PIXEL])


# image: the causes of its misses today (benchmarks/detect_realdata.py --misses)
CAUSES = {
    "img4.png": ["faint"], "crappy.jpg": ["edge"],
    # until the pipeline calls fine_pass.quiet_surroundings its old ring test drops img6's star at (809, 102)
    "img6.png": ["clutter"] if LOCAL_THRESHOLD else ["filtered", "clutter"],
    "roof.jpg": ["edge", "edge", "clutter", "faint", "blend", "edge"],
    "tree.jpg": ["faint", "faint", "faint", "clutter", "faint"], "pleiades.jpg": ["blend", "faint", "faint"],
}


@pytest.mark.parametrize("name", list(IMAGES))
def test_every_miss_has_a_cause(results, detectors, name):
    """No matched star is lost for no reason: each miss is at the border, blended, in clutter or
    below the fine pass's threshold (never a significant, isolated star on open sky that a filter
    dropped), and a faint one stands where the fine image has unconfirmed peaks as significant."""
    det, ref = results[name]
    found = misses(load_image(name), detectors[name], det, ref)
    assert [m.cause for m in found] == CAUSES.get(name, [])
    assert all(m.competing >= 10 for m in found if m.cause == "faint")


@pytest.mark.parametrize("name", list(IMAGES))
def test_spots_in_busy_rings_kept_by_their_own_clutter(detectors, name):
    """fine_pass.quiet_surroundings: of the fine pass's spots whose raw ring is busier than
    MAX_RING_NOISE, those that stand 1.5 times the threshold above their ring in the fine image
    are kept, and on open sky (every image but tree.jpg's leaves) each is a matched or a Hipparcos
    star; img6's matched star at (809.2, 102.0), busy only through the rounding of its 8-bit
    pixels, is one of them."""
    detector, ref = detectors[name], reference(name)
    fine, _, noise, (data, _) = significance_maps(load_image(name), detector)
    fine = fine.astype(np.float32)
    regions = fine_regions(data, None, detector.kernel, detector.kernel_px, detector.tile_px, detector.fine_sigma,
                           detector.grow_sigma, 1, snr=fine)
    peak = regions.argmax(fine[regions.y, regions.x])
    x, y = regions.x[peak].astype(float), regions.y[peak].astype(float)
    busy = ring_noise_ratio(data, x, y, noise) > MAX_RING_NOISE
    kept = busy & quiet_surroundings(data, fine, regions, x, y, noise, detector.fine_sigma)
    known_x, known_y = np.concatenate([ref.x, ref.hip_x]), np.concatenate([ref.y, ref.hip_y])
    confirmed = np.hypot(x[:, None] - known_x[None], y[:, None] - known_y[None]).min(axis=1) < 2 * PIXEL
    assert kept.any() and (busy & ~kept).any()
    assert np.sum(kept & ~confirmed) <= (3 if name == "tree.jpg" else 0)
    if name == "img6.png":
        assert kept[np.argmin(np.hypot(x - 809.2, y - 102.0))]
