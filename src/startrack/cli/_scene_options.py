"""Options that describe a simulated scene: camera, attitude, sensor, epoch (shared by simulate and demo)."""

from __future__ import annotations

import argparse
import dataclasses
import math
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..camera import Camera, get_preset
from ..errors import InvalidInputError
from ..frames import boresight, random_rotations, rotation_from_radec_roll
from ..simulate import PASSBANDS, FrameTiming, NoiseModel, Sensor, SkyBackground, get_sensor_preset, simulate_frame
from ..solve import DEFAULT_EPOCH_JYEAR
from ._common import epoch_option

DEFAULT_FOV_DEG = 15.0
DEFAULT_SIZE_PX = (1024, 1024)


def add_scene_options(parser: argparse.ArgumentParser) -> None:
    """Camera, attitude, sensor, --epoch and --seed options."""
    cam = parser.add_argument_group("camera (a preset, or a pinhole camera from FOV and size)")
    cam.add_argument("--camera", metavar="PRESET", help="camera preset (see startrack.camera.PRESETS)")
    cam.add_argument("--fov-deg", type=float, metavar="F", help=f"horizontal FOV (default {DEFAULT_FOV_DEG:g})")
    cam.add_argument("--width", type=int, metavar="W", help=f"width in px (default {DEFAULT_SIZE_PX[0]})")
    cam.add_argument("--height", type=int, metavar="H", help=f"height in px (default {DEFAULT_SIZE_PX[1]})")
    att = parser.add_argument_group("attitude (default: uniformly random from --seed)")
    att.add_argument("--ra-deg", type=float, help="boresight right ascension")
    att.add_argument("--dec-deg", type=float, help="boresight declination")
    att.add_argument("--roll-deg", type=float, default=0.0, help="roll (startrack.frames definition)")
    sen = parser.add_argument_group("sensor")
    sen.add_argument("--sensor", default="generic-cmos", help="sensor preset (default generic-cmos)")
    sen.add_argument("--exposure-s", type=float, help="exposure time (default: the sensor's)")
    sen.add_argument("--max-mag", type=float, default=7.5, help="faintest catalog star rendered (V, default 7.5)")
    sen.add_argument("--no-noise", action="store_true", help="render the expected image without noise")
    parser.add_argument("--epoch", type=float, metavar="YEAR",
                        help=f"epoch of the star positions, Julian year (default {DEFAULT_EPOCH_JYEAR:g}, "
                             "the default of the solvers)")
    parser.add_argument("--seed", type=int, help="random seed (attitude and noise), >= 0; default: fresh")


def scene_camera(args: argparse.Namespace) -> Camera:
    """The preset, or a pinhole camera from --fov-deg, --width, --height."""
    if args.camera:
        given = [name for name, value in (("--fov-deg", args.fov_deg), ("--width", args.width),
                                          ("--height", args.height)) if value is not None]
        if given:
            raise InvalidInputError(f"--camera fixes the FOV and size; leave out {', '.join(given)}")
        return get_preset(args.camera)
    width = args.width if args.width is not None else DEFAULT_SIZE_PX[0]
    height = args.height if args.height is not None else DEFAULT_SIZE_PX[1]
    fov_deg = args.fov_deg if args.fov_deg is not None else DEFAULT_FOV_DEG
    try:
        return Camera.from_fov(width, height, fov_deg, name="pinhole")
    except InvalidInputError as exc:
        options = f"--fov-deg {fov_deg:g} --width {width} --height {height}"
        raise InvalidInputError(f"pinhole camera {options}: {exc}") from None


def scene_attitude(args: argparse.Namespace, rng: np.random.Generator) -> Rotation:
    given = [v is not None for v in (args.ra_deg, args.dec_deg)]
    if any(given) and not all(given):
        raise InvalidInputError("give both --ra-deg and --dec-deg (and optionally --roll-deg), or neither")
    if not any(given):
        return random_rotations(None, rng)
    if not -90.0 <= args.dec_deg <= 90.0:
        raise InvalidInputError(f"--dec-deg must be between -90 and 90, got {args.dec_deg:g}")
    angles = (args.ra_deg, args.dec_deg, args.roll_deg)
    if not all(math.isfinite(v) for v in angles):
        raise InvalidInputError("--ra-deg, --dec-deg and --roll-deg must be finite numbers")
    return rotation_from_radec_roll(*(math.radians(v) for v in angles))


def scene_sensor(args: argparse.Namespace) -> Sensor:
    sensor = get_sensor_preset(args.sensor)
    if args.exposure_s is not None:
        if not args.exposure_s > 0:
            raise InvalidInputError(f"--exposure-s must be positive, got {args.exposure_s:g}")
        sensor = sensor.with_exposure(args.exposure_s)
    return sensor


def scene_epoch(args: argparse.Namespace) -> float:
    """The checked --epoch, or the solvers' default, as a Julian year."""
    epoch = epoch_option(args)
    return DEFAULT_EPOCH_JYEAR if epoch is None else epoch


def scene_seed(args: argparse.Namespace) -> int:
    """The seed to use: the given one, or a fresh one (printed so the run can be repeated)."""
    if args.seed is None:
        return int(np.random.default_rng().integers(2**31))
    if args.seed < 0:
        raise InvalidInputError(f"--seed must be a whole number >= 0, got {args.seed}")
    return args.seed


def simulate_scene(args: argparse.Namespace):
    """Check the scene options and render the frame.

    The options of :func:`add_render_options` (rate, noise switches, detector effects, sky
    background, optics) are used when the parser has them; ``startrack demo`` has only the
    scene options and renders a still frame with all noise on (or none with --no-noise).

    Returns
    -------
    seed : int
        The seed used (given or fresh).
    sim : startrack.simulate.SimulatedImage
        ``sim.image`` in ADU and ``sim.truth``.
    """
    seed = scene_seed(args)
    camera, sensor, epoch = scene_camera(args), render_sensor(args), scene_epoch(args)
    rng = np.random.default_rng(seed)
    rot = scene_attitude(args, rng)
    sim = simulate_frame(camera, rot, max_mag=args.max_mag, sensor=sensor, rng=rng, noise=noise_model(args),
                         epoch_jyear=epoch, rate_rad_s=scene_rate(args),
                         timing=FrameTiming(line_time_s=getattr(args, "line_time_s", None) or 0.0),
                         sky_background=sky_background(args, rot))
    return seed, sim


def add_render_options(parser: argparse.ArgumentParser) -> None:
    """Motion, noise switches, detector effects, sky background and optics (startrack simulate)."""
    mot = parser.add_argument_group("motion")
    mot.add_argument("--rate-deg-s", type=float, nargs=3, metavar=("WX", "WY", "WZ"),
                     help="angular rate of the camera in the camera frame, deg/s (default 0 0 0)")
    mot.add_argument("--line-time-s", type=float, metavar="S", help="rolling shutter: delay between rows, s")
    noi = parser.add_argument_group("noise switches (all on by default)")
    for term in ("shot", "dark", "read", "bias", "quantize", "saturate", "background"):
        noi.add_argument(f"--no-{term}", action="store_true", help=f"leave out the {term} term")
    noi.add_argument("--blooming", action="store_true", help="spill charge above the full well along columns")
    det = parser.add_argument_group("detector effects (off by default)")
    det.add_argument("--prnu", type=float, metavar="RMS", help="photo-response non-uniformity, fraction rms")
    det.add_argument("--dsnu", type=float, metavar="RMS", help="dark-signal non-uniformity, fraction rms")
    det.add_argument("--hot-pixels", type=float, metavar="FRACTION", help="fraction of hot pixels")
    det.add_argument("--dead-pixels", type=float, metavar="FRACTION", help="fraction of dead pixels")
    sky = parser.add_argument_group("sky background and optics")
    sky.add_argument("--sky-mag-arcsec2", type=float, metavar="MU",
                     help="sky surface brightness, V mag per arcsec^2 (default: none)")
    sky.add_argument("--zodiacal", action="store_true", help="sky from the coarse zodiacal model at the boresight")
    sky.add_argument("--stray-e-s", type=float, metavar="RATE", help="stray light, e- per s per pixel")
    sky.add_argument("--psf", choices=("gaussian", "airy"), help="PSF shape (default: the sensor's)")
    sky.add_argument("--psf-sigma-px", type=float, metavar="SIGMA", help="Gaussian PSF sigma, px")
    sky.add_argument("--passband", choices=sorted(PASSBANDS), help="spectral band (default: V)")


def noise_model(args: argparse.Namespace) -> NoiseModel:
    """The NoiseModel of --no-noise and the --no-TERM / --blooming switches."""
    if args.no_noise:
        return NoiseModel.ideal()
    off = {term: False for term in ("shot", "dark", "read", "bias", "quantize", "saturate", "background")
           if getattr(args, f"no_{term}", False)}
    return NoiseModel(blooming=bool(getattr(args, "blooming", False)), **off)


def scene_rate(args: argparse.Namespace) -> np.ndarray | None:
    """--rate-deg-s in rad/s, or None."""
    rate = getattr(args, "rate_deg_s", None)
    if rate is None:
        return None
    if not all(math.isfinite(v) for v in rate):
        raise InvalidInputError("--rate-deg-s needs three finite numbers (deg/s)")
    return np.radians(np.asarray(rate, dtype=float))


def render_sensor(args: argparse.Namespace) -> Sensor:
    """The sensor preset with --exposure-s, the detector effects, PSF and passband options."""
    sensor = scene_sensor(args)
    effects: dict[str, Any] = {name: getattr(args, option, None) for name, option in (
        ("prnu_rms", "prnu"), ("dsnu_rms", "dsnu"), ("hot_pixel_fraction", "hot_pixels"),
        ("dead_pixel_fraction", "dead_pixels"))}
    effects = {k: v for k, v in effects.items() if v is not None}
    optics = {k: v for k, v in (("psf", getattr(args, "psf", None)),
                                ("psf_sigma_px", getattr(args, "psf_sigma_px", None))) if v is not None}
    try:
        detector = dataclasses.replace(sensor.detector, **effects)
        sensor = dataclasses.replace(sensor, detector=detector, optics=dataclasses.replace(sensor.optics, **optics))
    except InvalidInputError as exc:
        raise InvalidInputError(f"detector or optics option: {exc}") from None
    band = getattr(args, "passband", None)
    return sensor if band is None else dataclasses.replace(sensor, passband=PASSBANDS[band])


def sky_background(args: argparse.Namespace, rot: Rotation) -> SkyBackground | None:
    """The SkyBackground of --sky-mag-arcsec2 / --zodiacal / --stray-e-s, or None."""
    mu, zodiacal, stray = (getattr(args, k, None) for k in ("sky_mag_arcsec2", "zodiacal", "stray_e_s"))
    if mu is not None and zodiacal:
        raise InvalidInputError("give --sky-mag-arcsec2 or --zodiacal, not both")
    if mu is None and not zodiacal and stray is None:
        return None
    stray_rate = 0.0 if stray is None else stray
    if zodiacal:
        return SkyBackground.zodiacal(boresight(rot), stray_e_s_px=stray_rate)
    return SkyBackground(mag_arcsec2=mu, stray_e_s_px=stray_rate)
