"""Every detection's centroid lies on the frame.

A blend that the full-resolution pass splits (``detect._fine_pass.add_new_regions``) can leave a
piece of mostly negative signal: its weighted sum is no star's flux and its centroid can be thrown
off the spot. Where the windowed centroid fails too, the piece is dropped; a centroid off the
frame counts as failed. Before, one such piece of orion_trees.jpg saved at JPEG quality 40 and
detected with a noise floor was put 0.27 px beyond the frame's edge, with a flux of -78, and
``solve_image`` raised (a star "outside the image"). Pieces whose windowed centroid converges are
kept: on orion_trees.jpg itself one is a star astrometry.net matched (a 47-pixel region whose sum
is negative).
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image as PILImage

from startrack.detect import StarDetector
from startrack.io import read_image

ORION = Path(__file__).resolve().parents[3] / "shared" / "realdata" / "smroid-cedar-solve" / "orion_trees.jpg"
FLOOR_PER_STEP = 0.05  # the floor (image units per quantization step) that threw the piece off the frame


def test_no_detection_lies_off_the_frame(tmp_path):
    path = tmp_path / "orion_q40.jpg"
    PILImage.open(ORION).save(path, quality=40)
    image = read_image(path)
    found = StarDetector(compression_noise=FLOOR_PER_STEP * image.compression_step).detect(image.data)
    h, w = image.data.shape
    assert len(found) > 50
    assert ((found.x >= -0.5) & (found.x <= w - 0.5) & (found.y >= -0.5) & (found.y <= h - 0.5)).all()
