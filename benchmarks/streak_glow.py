"""Smeared frames under glow: how many are solved from their streaks (``solve_streaked``).

Simulated catalog frames of a 12 deg, 1024 x 1024 generic-cmos camera (stars to V 7.5, 0.2 s
exposures at 2 deg/s about random axes: streaks of about 33 px) at random attitudes, with light
added in electrons and its shot noise (the sensor's gain is 1 e- per ADU, so straight onto the
counts): none, flat, a ramp across the frame (0 at the left edge),
or a limb's glow at the bottom edge falling by e over 150 px. Each condition gets the same frames,
axes and noise draws, so a change of the streak search is compared frame for frame. A frame is
solved right when its mid-exposure attitude is within 5 pixels of the truth.

    .venv/bin/python benchmarks/streak_glow.py [--frames 12] [--seed 3]
        [--glow none:0 flat:100 flat:200 ramp:200 ramp:400 limb:300 limb:1000]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from startrack import Camera
from startrack.frames import attitude_error, random_rotations
from startrack.rate import solve_streaked
from startrack.rate._streak_find import find_streak_candidates
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 12.0)
KINDS = ("none", "flat", "ramp", "limb")
LIMB_SCALE_PX = 150.0


def glow(kind: str, electrons: float, shape: tuple[int, int]) -> np.ndarray:
    """The light added (e- per pixel, ``shape``): ``electrons`` flat, at the ramp's right end, or
    at the limb's edge."""
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    if kind == "flat":
        return np.full(shape, electrons)
    if kind == "ramp":
        return electrons * xx / (shape[1] - 1)
    if kind == "limb":
        return electrons * np.exp(-(shape[0] - 1 - yy) / LIMB_SCALE_PX)
    return np.zeros(shape)


def run(kind: str, electrons: float, frames: int, seed: int) -> tuple[int, float]:
    """Frames solved right of ``frames``, and the median number of streak candidates."""
    rng = np.random.default_rng(seed)
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.2)
    solved, candidates = 0, []
    light = glow(kind, electrons, (CAMERA.height, CAMERA.width))
    for i, rot in enumerate(random_rotations(frames, rng)):
        axis = rng.normal(size=3)
        frame = simulate_frame(CAMERA, rot, max_mag=7.5, epoch_jyear=2025.0, sensor=sensor, rng=100 + i,
                               rate_rad_s=2.0 * DEG * axis / np.linalg.norm(axis))
        image = np.clip(frame.image + rng.poisson(light), 0, np.iinfo(frame.image.dtype).max).astype(frame.image.dtype)
        solution = solve_streaked(image, fov_deg=12.0, epoch=2025.0)
        solved += bool(solution.solved and attitude_error(frame.truth.rot_cam_from_icrs, solution.rot_cam_from_icrs)
                       < 5 * CAMERA.pixel_scale_arcsec * ARCSEC)
        candidates.append(len(find_streak_candidates(image)))
    return solved, float(np.median(candidates))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=12)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--glow", nargs="+", default=["none:0", "flat:100", "flat:200", "ramp:200", "ramp:400",
                                                      "limb:300", "limb:1000"],
                        help="KIND:ELECTRONS, KIND one of none, flat, ramp, limb")
    args = parser.parse_args(argv)
    conditions = []
    for item in args.glow:
        kind, _, value = item.partition(":")
        if kind not in KINDS or not value.replace(".", "", 1).isdigit():
            parser.error(f"--glow {item!r}: give KIND:ELECTRONS with KIND one of {', '.join(KINDS)}, e.g. ramp:200")
        conditions.append((kind, float(value)))
    print(f"{'glow':<12}{'e-':>7}{'solved':>10}{'candidates':>12}   ({args.frames} frames each, seed {args.seed})")
    for kind, electrons in conditions:
        solved, candidates = run(kind, electrons, args.frames, args.seed)
        print(f"{kind:<12}{electrons:>7g}{f'{solved}/{args.frames}':>10}{candidates:>12g}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
