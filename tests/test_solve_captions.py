"""Real photos with a saturated caption burnt in solve with no hint.

A camera's date stamp, a photographer's name or a logo in white breaks into saturated spots
brighter than every star. By brightness alone they filled the solver's first 20 pattern stars,
and the search timed out (5 s) on 31 of 120 such variants of the real photos (two of the six
here; docs/identification.md). Now the detector
rates clipped spots whose cores do not fill their ellipse (strokes, rings) as extended, against
the unsaturated stars' shapes (:mod:`startrack.detect._point_source`), and the search order takes
turns between the cells of the image (:func:`startrack.solve.spread_rounds`).

Truth: astrometry.net (../shared/realdata/truth.csv), as in test_realdata_solve.py.
"""

from __future__ import annotations

import pytest
from PIL import Image, ImageDraw, ImageFont

from startrack.frames import angle_between, radec_to_vector
from startrack.solve import solve_image
from startrack.units import ARCSEC, DEG

CAPTIONS = {
    "centred name": lambda w, h: [("(c) 2024 Night Sky Photo", max(30, h // 9), "centre")],
    "two-line stamp": lambda w, h: [("Canon EOS R6  ISO 6400\n2024-08-12 23:41:05", max(24, h // 14), "bottom left")],
}


def _font(size: int):
    try:
        return ImageFont.load_default(size=size)
    except (TypeError, OSError):  # Pillow < 10.1 or without FreeType: no scalable default font
        pytest.skip("this Pillow has no scalable default font (Pillow >= 10.1 with FreeType)")


def _captioned(path, caption: str, out):
    """The photo at ``path`` with ``caption`` drawn in white (255 in every channel), saved as
    ``out`` in the photo's own format (JPEG quality 90)."""
    image = Image.open(path).convert("RGB")
    w, h = image.size
    draw = ImageDraw.Draw(image)
    for text, size, where in CAPTIONS[caption](w, h):
        font = _font(size)
        left = (w - draw.textlength(text, font=font)) / 2 if where == "centre" else 10
        top = h / 2 if where == "centre" else h - 2.6 * size
        draw.text((left, top), text, font=font, fill=(255, 255, 255))
    image.save(out, quality=90) if out.suffix == ".jpg" else image.save(out)
    return out


@pytest.mark.parametrize("caption", sorted(CAPTIONS))
@pytest.mark.parametrize("name", ["roof.jpg", "img6.png", "crappy.jpg"])
def test_a_photo_with_a_saturated_caption_solves_with_no_hint(name, caption, truth_table, realdata_dir, tmp_path):
    row = next(r for r in truth_table if r["file"] == name)
    path = _captioned(realdata_dir / row["set"] / name, caption, tmp_path / f"captioned{(realdata_dir / name).suffix}")
    solution = solve_image(path)
    assert solution.solved, f"{name} with a {caption}: {solution.reason}"
    width, height = int(row["width"]), int(row["height"])
    centre_cam = solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2)
    centre_icrs = solution.rot_cam_from_icrs.inv().apply(centre_cam)
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    assert angle_between(centre_icrs, truth) < 2 * float(row["pixscale_arcsec"]) * ARCSEC  # 2 px
