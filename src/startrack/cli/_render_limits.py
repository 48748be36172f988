"""Range checks of the simulator's options, before anything is rendered (docs/io.md, "Limits").

Each limit keeps a frame's memory and time bounded; past it the simulator would ask for
terabytes (a PSF sigma of 1e6 px, stray light of 1e30 e-/s) or fail deep inside:

* the image (--width x --height) holds at most --max-pixels pixels (the limit of every image
  startrack reads, :mod:`startrack.io._limits`);
* the Gaussian PSF sigma is at most :data:`MAX_PSF_SIGMA_PX`;
* the camera turns at most :data:`MAX_TURN_PER_FRAME_DEG` during one frame (rate x (exposure +
  rows x line time));
* stray light adds at most :data:`MAX_STRAY_E_PER_FRAME` electrons per pixel in one exposure,
  and so does the sky of --sky-mag-arcsec2 (a surface brightness of -11 mag per arcsec^2 asked
  for 3e12 e- per pixel and 7 GB of memory; -100 failed with a numpy error).
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from ..errors import InvalidInputError
from ..io import ENV_VAR, resolve_max_pixels
from ._scene_options import DEFAULT_SIZE_PX, render_sensor, scene_camera

if TYPE_CHECKING:
    from ..simulate import Sensor

MAX_PSF_SIGMA_PX = 20.0
"""Largest Gaussian PSF sigma, px (a rendered star spans about 12 sigma)."""

MAX_TURN_PER_FRAME_DEG = 10.0
"""Largest angle the camera may turn during one frame, deg."""

MAX_STRAY_E_PER_FRAME = 1e9
"""Largest stray-light charge per pixel and exposure, e- (a full well holds 1e4 to 1e6)."""


def _check_size(args: argparse.Namespace) -> None:
    if getattr(args, "camera", None) or getattr(args, "rig", None) is not None:  # a rig's heads: checked by --rig
        return
    width = args.width if args.width is not None else DEFAULT_SIZE_PX[0]
    height = args.height if args.height is not None else DEFAULT_SIZE_PX[1]
    limit = resolve_max_pixels(getattr(args, "max_pixels", None))
    if width * height > limit:
        raise InvalidInputError(f"--width {width} --height {height} is {width * height:,} px, over the limit of "
                                f"{limit:,} px; raise it with --max-pixels (or {ENV_VAR}) if you mean it")


def _check_psf(args: argparse.Namespace) -> None:
    sigma = getattr(args, "psf_sigma_px", None)
    if sigma is not None and not 0.0 < sigma <= MAX_PSF_SIGMA_PX:
        raise InvalidInputError(f"--psf-sigma-px must be above 0 and at most {MAX_PSF_SIGMA_PX:g} px, got {sigma:g}")


def _check_motion(args: argparse.Namespace, exposure_s: float, rows: int) -> None:
    rate = getattr(args, "rate_deg_s", None)
    if rate is None:
        return
    span_s = exposure_s + (rows - 1) * (getattr(args, "line_time_s", None) or 0.0)
    turn = math.hypot(*rate) * span_s  # without numpy's overflow warning at 1e300 deg/s
    if turn > MAX_TURN_PER_FRAME_DEG:
        raise InvalidInputError(
            f"--rate-deg-s turns the camera {turn:.3g} deg during one frame ({span_s:.3g} s); at most "
            f"{MAX_TURN_PER_FRAME_DEG:g} deg is rendered: lower the rate, --exposure-s or --line-time-s")


def _check_stray(args: argparse.Namespace, exposure_s: float) -> None:
    stray = getattr(args, "stray_e_s", None)
    if stray is not None and not 0.0 <= stray * exposure_s <= MAX_STRAY_E_PER_FRAME:
        raise InvalidInputError(f"--stray-e-s {stray:g} gives {stray * exposure_s:.3g} e- per pixel in a "
                                f"{exposure_s:g} s exposure; valid: 0 to {MAX_STRAY_E_PER_FRAME:.0e}")


def _check_sky(args: argparse.Namespace, sensor: Sensor) -> None:
    mu = getattr(args, "sky_mag_arcsec2", None)  # finite: check_finite_options refused NaN and inf
    if mu is None:
        return
    from ..simulate import SkyBackground

    electrons = SkyBackground(mag_arcsec2=mu).sky_electrons_px(scene_camera(args), sensor)
    if electrons > MAX_STRAY_E_PER_FRAME:
        brightest = mu + 2.5 * math.log10(electrons / MAX_STRAY_E_PER_FRAME)
        raise InvalidInputError(f"--sky-mag-arcsec2 {mu:g} gives {electrons:.3g} e- per pixel in a "
                                f"{sensor.exposure_s:g} s exposure; valid: at most {MAX_STRAY_E_PER_FRAME:.0e} e-, "
                                f"a sky of {brightest:.1f} mag per arcsec^2 or fainter with this camera")


def check_render_options(args: argparse.Namespace) -> None:
    """Refuse simulator options outside the limits of the module docstring.

    Raises
    ------
    InvalidInputError
        Naming the option, the value and what is valid.
    """
    _check_size(args)
    _check_psf(args)
    sensor = render_sensor(args)
    exposure_s = sensor.exposure_s
    rows = 1 if getattr(args, "rig", None) is not None else scene_camera(args).height
    if not math.isfinite(exposure_s):
        return
    _check_motion(args, exposure_s, rows)
    _check_stray(args, exposure_s)
    _check_sky(args, sensor)
