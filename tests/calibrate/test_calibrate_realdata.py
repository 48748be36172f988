"""Self-calibration on the real images of ../shared/realdata: the calibrated model never fits worse
than the pinhole on the same stars, clearly better where the lens shows, and its WCS stays close to
astrometry.net's across the whole frame."""

import csv
from pathlib import Path

import numpy as np
import pytest

from startrack.calibrate._selfcal import self_calibrate
from startrack.io._wcs import read_wcs, solution_wcs

TRUTH_CSV = Path(__file__).resolve().parents[2].parent / "shared" / "realdata" / "truth.csv"


def _names() -> list[str]:
    if not TRUTH_CSV.exists():
        return []
    with open(TRUTH_CSV, newline="") as fh:
        return [row["file"] for row in csv.DictReader(fh)]


NAMES = _names()

IMPROVED = {"crappy.jpg", "orion_trees.jpg", "pleiades.jpg", "roof.jpg"}
"""Images whose lens distortion is significant against their centroid noise (measured 15-40 %
lower RMS; roof.jpg 17 %, k2 only, since the detector's full-resolution pass); on the others every
distortion term is pruned, by the 3-sigma rule or by the joint F-test against the pinhole
(img3.png: 12 stars of a 6 deg field), and the model is the pinhole's."""

EXTRAPOLATED = {"tree.jpg": "its stars reach x = 410 of 512 (a tree covers the rest); f, aspect, cx and k2 fitted "
                            "on them (0.33 -> 0.22 px, F-test passed at p = 6e-7) put the principal point 81 px off "
                            "centre and bend the empty right edge up to 19 px from astrometry.net's WCS (3.3 px RMS)"}
"""Known failures: a calibration that fits its stars and extrapolates badly beyond them."""


def wcs_difference_px(ours, truth, width, height, pixel_arcsec, n=25):
    gx, gy = np.meshgrid(np.linspace(0, width - 1, n), np.linspace(0, height - 1, n))
    x, y = gx.ravel(), gy.ravel()
    sep = ours.pixel_to_world(x, y).separation(truth.pixel_to_world(x, y)).arcsec / pixel_arcsec
    return float(np.sqrt(np.mean(sep**2))), float(np.max(sep))


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(reason=EXTRAPOLATED[n], strict=True))
                                  if n in EXTRAPOLATED else n for n in NAMES])
def test_self_calibration_on_real_images(name, truth_table, realdata_dir):
    row = next(r for r in truth_table if r["file"] == name)
    result = self_calibrate(realdata_dir / row["set"] / name, fov_range_deg=(5.0, 35.0))
    assert result.solution.solved and result.calibration is not None, result.reason
    assert result.calibrated_rms_px <= result.pinhole_rms_px * 1.001
    if name in IMPROVED:
        assert result.calibrated_rms_px < 0.85 * result.pinhole_rms_px
    else:  # every term pruned: the camera is the pinhole, nothing carried over from earlier rounds
        cam = result.calibration.camera
        assert not cam.has_distortion
        assert (cam.cx, cam.cy, cam.fy) == ((cam.width - 1) / 2, (cam.height - 1) / 2, cam.fx)
    truth = read_wcs(realdata_dir / row["set"] / "truth" / (name.rsplit(".", 1)[0] + ".wcs"))
    ours = solution_wcs(result.solution.rot_cam_from_icrs, result.solution.camera)
    rms_px, max_px = wcs_difference_px(ours, truth, int(row["width"]), int(row["height"]),
                                       float(row["pixscale_arcsec"]))
    assert rms_px < 2.0
    assert max_px < 7.0
