"""Fixed-mount repeatability (Fowler 2013 Ch. 7 / 9) on a synthetic night, and its plots."""

import numpy as np
import pytest
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from startrack.analysis._calibration_plots import plot_distortion, plot_repeatability, plot_residuals
from startrack.calibrate._ground import rotation_enu_from_icrs
from startrack.calibrate._repeatability import error_budget, repeatability
from startrack.calibrate._sites import BUILTIN_SITES
from startrack.camera import get_preset
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error
from startrack.units import ARCMIN, ARCSEC

SITE = BUILTIN_SITES["logan-ut-2012"]
MOUNT = Rotation.from_euler("zyx", [30.0, -50.0, 5.0], degrees=True)  # rot_cam_from_enu


def _night(n=60, pointing_arcmin=0.0, roll_arcmin=0.0, rng=0):
    gen = np.random.default_rng(rng)
    times = Time("2012-10-05T03:00:00", scale="utc") + TimeDelta(np.arange(n) * 120.0, format="sec")
    rots = []
    for t in times:
        err = np.concatenate([gen.normal(0, pointing_arcmin * ARCMIN, 2), gen.normal(0, roll_arcmin * ARCMIN, 1)])
        rots.append(Rotation.from_rotvec(err) * MOUNT * rotation_enu_from_icrs(t, SITE))
    return times, rots


def test_a_perfect_sequence_has_no_error_and_finds_the_mount():
    times, rots = _night(20)
    result = repeatability(times, rots, SITE)
    assert attitude_error(MOUNT, result.mount) < 1e-3 * ARCSEC
    assert np.max(result.total_rad) < 1e-3 * ARCSEC


def test_pointing_and_roll_are_separated():
    times, rots = _night(200, pointing_arcmin=0.5, roll_arcmin=2.0, rng=3)
    result = repeatability(times, rots, SITE)
    summary = result.summary_arcmin()
    # Rayleigh mean of 0.5' per axis is 0.63'; half-normal mean of 2' is 1.6'
    assert summary["pointing"][0] == pytest.approx(0.5 * np.sqrt(np.pi / 2), rel=0.15)
    assert summary["roll"][0] == pytest.approx(2.0 * np.sqrt(2 / np.pi), rel=0.15)
    assert result.mount_standard_error_rad == pytest.approx(np.sqrt((0.25 + 0.25 + 4) / 3) * ARCMIN / np.sqrt(200),
                                                            rel=0.2)
    budget = error_budget(result, lens_sigma_px=0.259, pixel_scale_arcsec=1.14 * 60, threshold_rad=0.15 * ARCMIN)
    assert budget["lens"] / ARCMIN == pytest.approx(0.295, abs=0.001)  # Fowler 2013 Table 4.4: 0.2953'
    assert budget["atmosphere"] / ARCSEC == pytest.approx(4.2)
    assert budget["rss"] < budget["linear_sum"]


def test_plots_are_written(tmp_path):
    times, rots = _night(10, 0.5, 1.0)
    plot_repeatability(repeatability(times, rots, SITE), tmp_path / "rep.png")
    cam = get_preset("droid-x2")
    plot_distortion(cam, tmp_path / "dist.png")
    rng = np.random.default_rng(1)
    x, y = rng.uniform(0, cam.width, 50), rng.uniform(0, cam.height, 50)
    plot_residuals(x, y, rng.normal(0, 0.2, (50, 2)), cam, tmp_path / "res.png")
    assert all((tmp_path / f).stat().st_size > 5000 for f in ("rep.png", "dist.png", "res.png"))


def test_mismatched_inputs_raise():
    times, rots = _night(3)
    with pytest.raises(InvalidInputError, match="one time per attitude"):
        repeatability(times, rots[:2], SITE)
