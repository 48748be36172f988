"""Seed 000 Table 8.2: time to match a 14-frame sequence, by matching method, ours beside the seed's.

The seed (Huffman 2006, §7.4 and Table 8.2; notes ``seed-000.md`` §2.11) timed in Matlab, for 14
slow-rate frames, the whole chain per frame (threshold, centroid, match, QUEST): the
frame-to-frame triangle match and rate match (relative attitude, chained from the first frame's
absolute one) and the n-vertex lost-in-space match for n = 3, 4, 5 (absolute every frame).
Here the same chain runs on 14 simulated frames (1024 x 1024 px, 15 deg FOV, generic CMOS
sensor, 0.2 deg/s about a random axis, one frame per second): detection
(``startrack.detect``), then

- ``triangle``: :func:`startrack.track.relative.triangle_match` between consecutive frames;
- ``rate``: :func:`startrack.track.relative.rate_match` with the rate of the first two absolute
  attitudes;
- ``nvertex-n``: ``solve_stars(method="nvertex-n", camera=...)`` on every frame;
- ``quads`` (our default) on every frame, for reference.

The relative methods start from a ``quads`` solve of frame 0 (counted in their time). Printed:
total and per-frame time, the seed's, the ranking, and the attitude error at the last frame
(relative chaining accumulates error, absolute matching does not: the seed's point).

Usage::

    python benchmarks/seed000_table82.py [--seed 1] [--repeats 3]
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera, solve_stars
from startrack.detect import StarDetector
from startrack.frames import attitude_error, random_rotations
from startrack.rate.from_attitudes import rate_between
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.track.relative import rate_match, triangle_match
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 15.0)
FRAMES, DT_S, RATE_DEG_S = 14, 1.0, 0.2
SEED_TOTAL_S = {"triangle": 9.06, "rate": 15.12, "nvertex-3": 8.30, "nvertex-4": 8.27, "nvertex-5": 8.33}
"""Seed 000 Table 8.2 (Matlab, 14 frames, threshold + centroid + match + QUEST)."""


def frames(seed: int) -> tuple[list[np.ndarray], list[Rotation]]:
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    rate = axis / np.linalg.norm(axis) * RATE_DEG_S * DEG
    start = random_rotations(None, rng)
    truths = [Rotation.from_rotvec(-rate * DT_S * k) * start for k in range(FRAMES)]
    sensor = get_sensor_preset("generic-cmos")
    images = [simulate_frame(CAMERA, t, max_mag=7.5, sensor=sensor, rng=seed * 100 + k).image
              for k, t in enumerate(truths)]
    return images, truths


def _vectors(found) -> np.ndarray:
    return CAMERA.pixel_to_vector(found.x, found.y)


def run_absolute(images, method: str) -> list[Rotation | None]:
    out = []
    for image in images:
        found = StarDetector().detect(image)
        sol = solve_stars(found.x, found.y, flux=found.flux, camera=CAMERA, method=method)
        out.append(sol.rot_cam_from_icrs if sol.solved else None)
    return out


def run_relative(images, method: str) -> list[Rotation | None]:
    """Absolute attitude of frame 0 (and 1, for the rate), then chained relative attitudes."""
    tol = 3 * CAMERA.pixel_scale_arcsec * ARCSEC
    found = [StarDetector().detect(images[0])]
    first = solve_stars(found[0].x, found[0].y, flux=found[0].flux, camera=CAMERA)
    out = [first.rot_cam_from_icrs if first.solved else None]
    rate = None
    for k in range(1, len(images)):
        found.append(StarDetector().detect(images[k]))
        prev, cur = _vectors(found[k - 1]), _vectors(found[k])
        if out[-1] is None:
            out.append(None)
            continue
        if method == "rate" and rate is None:  # the rate comes from two absolute attitudes
            sol = solve_stars(found[k].x, found[k].y, flux=found[k].flux, camera=CAMERA)
            out.append(sol.rot_cam_from_icrs if sol.solved else None)
            rate = rate_between(out[-2], out[-1], DT_S) if sol.solved else None
            continue
        rel = rate_match(prev, cur, rate, DT_S, tol) if method == "rate" else triangle_match(prev, cur, tol)
        out.append(rel.rot_cam2_from_cam1 * out[-1] if rel.rot_cam2_from_cam1 is not None else None)
    return out


def measure(images, truths, method: str, repeats: int) -> dict:
    runner = run_relative if method in ("triangle", "rate") else run_absolute
    best, result = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = runner(images, method)
        best = min(best, time.perf_counter() - t0)
    pixel = CAMERA.pixel_scale_arcsec * ARCSEC
    errors = [np.nan if r is None else attitude_error(t, r) / pixel for r, t in zip(result, truths, strict=True)]
    return {"method": method, "total_s": best, "solved": int(np.sum(np.isfinite(errors))),
            "last_error_px": errors[-1], "max_error_px": float(np.nanmax(errors))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3, help="best of this many runs per method")
    args = parser.parse_args(argv)
    images, truths = frames(args.seed)
    for method in ("quads", "nvertex-3"):  # load the databases before timing
        run_absolute(images[:1], method)
    methods = ["triangle", "rate", "nvertex-3", "nvertex-4", "nvertex-5", "quads"]
    rows = [measure(images, truths, m, args.repeats) for m in methods]
    print(f"{'method':<10} {'ours 14 frames (s)':>18} {'per frame (ms)':>15} {'seed (s)':>9} {'solved':>7} "
          f"{'last-frame error (px)':>22} {'max error (px)':>15}")
    for r in rows:
        seed = SEED_TOTAL_S.get(r["method"])
        print(f"{r['method']:<10} {r['total_s']:>18.3f} {r['total_s'] / FRAMES * 1e3:>15.1f} "
              f"{'' if seed is None else f'{seed:.2f}':>9} {r['solved']:>4}/{FRAMES} {r['last_error_px']:>22.2f} "
              f"{r['max_error_px']:>15.2f}")
    ours = [r["method"] for r in sorted(rows, key=lambda r: r["total_s"]) if r["method"] in SEED_TOTAL_S]
    seed = sorted(SEED_TOTAL_S, key=SEED_TOTAL_S.get)
    print(f"ranking, fastest first: ours {' < '.join(ours)}; seed {' < '.join(seed)}")
    print(f"frames: {FRAMES} at {DT_S:g} s, {RATE_DEG_S:g} deg/s; times are the best of {args.repeats} runs and "
          "include detection", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
