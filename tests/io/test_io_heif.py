"""HEIC / HEIF photos (:mod:`startrack.io._heif`): read with their size, bit depth and EXIF, refused
cleanly when too large or broken, and solved like any photo."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image as PILImage
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.errors import ImageReadError
from startrack.io import IMAGE_SUFFIXES, read_image
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image

pillow_heif = pytest.importorskip("pillow_heif")  # the "heif" extra, installed with the test tools

EXIF_IFD, DATE_TIME_ORIGINAL = 0x8769, 0x9003


def _exif(when: str) -> bytes:
    exif = PILImage.Exif()
    exif.get_ifd(EXIF_IFD)[DATE_TIME_ORIGINAL] = when
    return exif.tobytes()


def _save(path, rgb: np.ndarray, mode: str = "RGB", **kwargs) -> None:
    height, width = rgb.shape[:2]
    pillow_heif.from_bytes(mode=mode, size=(width, height), data=rgb.tobytes()).save(path, quality=95, **kwargs)


@pytest.fixture(scope="module")
def star_photo(tmp_path_factory):
    """A simulated 15 deg frame as an 8-bit colour HEIC with an EXIF time, and its truth."""
    camera, truth = Camera.from_fov(640, 480, 15.0), Rotation.random(random_state=21)
    sim = simulate_frame(camera, truth, max_mag=7.0, rng=3, sensor=get_sensor_preset("generic-cmos"))
    sky, spread = np.median(sim.image), np.subtract(*np.percentile(sim.image, [84.13, 15.87])) / 2
    grey = np.clip((sim.image - sky) * (3.0 / spread) + 30.0, 0, 255)  # the sky at 30 DN, its noise 3 DN
    rgb = np.repeat(grey.astype(np.uint8)[:, :, None], 3, axis=2)
    path = tmp_path_factory.mktemp("heif") / "stars.heic"
    _save(path, rgb, exif=_exif("2024:07:02 00:00:00"))
    return path, truth, camera


def test_heic_reads_with_its_size_colour_and_exif(star_photo):
    path, _, camera = star_photo
    image = read_image(path)
    assert image.data.shape == (camera.height, camera.width) and image.colour and image.bit_depth == 8
    assert image.header["DateTimeOriginal"] == "2024:07:02 00:00:00"
    assert ".heic" in IMAGE_SUFFIXES


def test_ten_bit_heic_keeps_its_counts(tmp_path):
    counts = (np.arange(64 * 80 * 3).reshape(64, 80, 3) % 1024).astype(np.uint16)
    _save(tmp_path / "ten.heic", counts << 6, mode="RGB;16")
    image = read_image(tmp_path / "ten.heic", channel="g")
    assert image.bit_depth == 10 and image.data.dtype == np.uint16
    assert 900 <= image.data.max() <= 1023  # counts of 10 bits (lossy coding moves them a little)


def test_heic_over_the_limit_or_broken_is_refused_by_name(star_photo, tmp_path):
    path = star_photo[0]
    with pytest.raises(ImageReadError, match="640 x 480"):
        read_image(path, max_pixels=1000)
    broken = tmp_path / "broken.heic"
    broken.write_bytes(path.read_bytes()[:400])
    with pytest.raises(ImageReadError, match="broken.heic"):
        read_image(broken)


def test_heic_photo_solves_with_the_epoch_of_its_exif(star_photo):
    path, truth, camera = star_photo
    solution = solve_image(path)
    assert solution.solved, solution.reason
    boresight = np.degrees((solution.rot_cam_from_icrs * truth.inv()).magnitude()) * 3600.0
    assert boresight < 5 * camera.pixel_scale_arcsec  # arcsec: within 5 pixels
    assert solution.epoch_source == "DateTimeOriginal" and solution.epoch_jyear == pytest.approx(2024.5, abs=0.01)
