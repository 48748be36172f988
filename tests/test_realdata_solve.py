"""The eight real sky images solve from pixels, given only a 5-35 deg FOV range or nothing at all
(the default search, 3-100 deg).

Truth: astrometry.net (../shared/realdata/truth.csv). Its RA/Dec is the direction of the image
centre ((W - 1) / 2, (H - 1) / 2) in our 0-based convention, and its ``roll_tetra3_deg`` is the
roll that :mod:`startrack.frames` defines (checked in test_frames.py).
"""

import csv
from pathlib import Path

import numpy as np
import pytest

from startrack.frames import angle_between, radec_to_vector
from startrack.solve import solve_image
from startrack.units import ARCSEC, DEG

ROWS = Path(__file__).resolve().parents[1].parent / "shared" / "realdata" / "truth.csv"


def _names() -> list[str]:
    if not ROWS.exists():
        return []
    with open(ROWS, newline="") as fh:
        return [row["file"] for row in csv.DictReader(fh)]


NAMES = _names()


@pytest.mark.parametrize("fov_range_deg", [(5.0, 35.0), None], ids=["5-35 deg", "no hint"])
@pytest.mark.parametrize("name", NAMES)
def test_real_image_solves_within_two_pixels_and_a_fifth_of_a_degree(name, fov_range_deg, truth_table, realdata_dir):
    row = next(r for r in truth_table if r["file"] == name)
    solution = solve_image(realdata_dir / row["set"] / name, fov_range_deg=fov_range_deg)
    detections = solution.detections
    assert solution.solved, f"{name}: {solution.reason}"
    width, height = int(row["width"]), int(row["height"])
    centre_cam = solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2)
    centre_icrs = solution.rot_cam_from_icrs.inv().apply(centre_cam)
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    pixel = float(row["pixscale_arcsec"]) * ARCSEC
    assert angle_between(centre_icrs, truth) < 2 * pixel
    roll_error_deg = (solution.roll_deg - float(row["roll_tetra3_deg"]) + 180.0) % 360.0 - 180.0
    assert abs(roll_error_deg) < 0.2
    assert solution.fov_deg == pytest.approx(float(row["fov_w_pinhole_deg"]), rel=0.01)
    assert len(solution.matches) >= min(int(row["n_match"]), 8)
    assert np.all(solution.matches.det_index < len(detections))
