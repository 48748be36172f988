"""Options that describe a simulated scene: camera, attitude, sensor (shared by simulate and demo)."""

from __future__ import annotations

import argparse
import math

import numpy as np
from scipy.spatial.transform import Rotation

from ..camera import Camera, get_preset
from ..errors import InvalidInputError
from ..frames import random_rotations, rotation_from_radec_roll
from ..simulate import Sensor, get_sensor_preset


def add_scene_options(parser: argparse.ArgumentParser, *, default_fov_deg: float = 15.0,
                      default_size: tuple[int, int] = (1024, 1024)) -> None:
    cam = parser.add_argument_group("camera")
    cam.add_argument("--camera", metavar="PRESET", help="camera preset (see startrack.camera.PRESETS)")
    cam.add_argument("--fov-deg", type=float, metavar="F",
                     help=f"pinhole camera: horizontal FOV (default {default_fov_deg})")
    cam.add_argument("--width", type=int, default=default_size[0], help="pinhole camera: width in px")
    cam.add_argument("--height", type=int, default=default_size[1], help="pinhole camera: height in px")
    att = parser.add_argument_group("attitude (default: uniformly random from --seed)")
    att.add_argument("--ra-deg", type=float, help="boresight right ascension")
    att.add_argument("--dec-deg", type=float, help="boresight declination")
    att.add_argument("--roll-deg", type=float, default=0.0, help="roll (startrack.frames definition)")
    sen = parser.add_argument_group("sensor")
    sen.add_argument("--sensor", default="generic-cmos", help="sensor preset (default generic-cmos)")
    sen.add_argument("--exposure-s", type=float, help="exposure time (default: the sensor's)")
    sen.add_argument("--max-mag", type=float, default=7.5, help="faintest catalog star rendered (V)")
    sen.add_argument("--no-noise", action="store_true", help="render the expected image without noise")
    parser.add_argument("--seed", type=int, help="random seed (attitude and noise); default: fresh")
    parser.set_defaults(default_fov_deg=default_fov_deg)


def scene_camera(args: argparse.Namespace) -> Camera:
    if args.camera and args.fov_deg is not None:
        raise InvalidInputError("give --camera or --fov-deg, not both")
    if args.camera:
        return get_preset(args.camera)
    return Camera.from_fov(args.width, args.height, args.fov_deg if args.fov_deg is not None else args.default_fov_deg,
                           name="pinhole")


def scene_attitude(args: argparse.Namespace, rng: np.random.Generator) -> Rotation:
    given = [v is not None for v in (args.ra_deg, args.dec_deg)]
    if any(given) and not all(given):
        raise InvalidInputError("give both --ra-deg and --dec-deg (and optionally --roll-deg), or neither")
    if not any(given):
        return random_rotations(None, rng)
    if not -90.0 <= args.dec_deg <= 90.0:
        raise InvalidInputError(f"--dec-deg must be between -90 and 90, got {args.dec_deg:g}")
    return rotation_from_radec_roll(*(math.radians(v) for v in (args.ra_deg, args.dec_deg, args.roll_deg)))


def scene_sensor(args: argparse.Namespace) -> Sensor:
    sensor = get_sensor_preset(args.sensor)
    if args.exposure_s is not None:
        if not args.exposure_s > 0:
            raise InvalidInputError(f"--exposure-s must be positive, got {args.exposure_s:g}")
        sensor = sensor.with_exposure(args.exposure_s)
    return sensor


def scene_seed(args: argparse.Namespace) -> int:
    """The seed to use: the given one, or a fresh one (printed so the run can be repeated)."""
    return args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % 2**31)
