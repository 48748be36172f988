"""The star-camera simulator: speed, against a plain per-pixel loop, and the seed reproductions.

Timings (``time.perf_counter``, median of ``--repeats`` runs after one warm-up, on 1024 x 1024
frames of a 15 deg pinhole camera with the ``generic-cmos`` sensor):

- **point frame**: 30 stars at random positions (``render_stars``) with every noise source on:
  shot noise, dark current, read noise, bias, gain, 12-bit quantisation, full well, a 21.5 mag
  arcsec^-2 sky, stray light, hot and dead pixels; target under 30 ms;
- the same **with PRNU and DSNU** (every pixel then has its own expectation and is drawn one by
  one: the slow path of :mod:`startrack.simulate._noise`);
- **streaked frame**: 0.5 s at 1 deg/s, the Hipparcos sky to V 7.5 (about 190 stars), every noise
  source; target under 150 ms median; and the same with only 30 stars.

Each simulated frame is also rendered by a plain Python loop (pixel by pixel for the point frame;
sample by sample and stamp pixel by stamp pixel for the streak, then pixel by pixel for the noise)
on the same inputs (shot, dark, read noise, gain, bias, quantisation, full well; the loop leaves
out the fixed pattern); the table prints the ratio, and the largest difference of the loop's
noise-free star image from the simulator's, relative to the brightest pixel.

Seed reproductions, run as campaigns of their shipped specs (``seed_campaign.py``; conditions
and results in docs/seed_tables_huffman_jacobs_samaan.md), each printing ours beside the seed's:

- Samaan 2002 Table 1 (``samaan2002-table1-smear-rate``): the largest rate for negligible smear
  (0.1 px) with StarNav I, and the smear the simulator renders at it;
- Huffman 2006 Table 5.1 (``huffman2006-table5.1-star-availability``): the magnitude limit that
  guarantees 4 or 6 stars in every field (a 1 deg Fibonacci lattice of boresights), cone and
  square fields, with Hipparcos-2;
- Huffman 2006 Table 5.3 (``huffman2006-table5.3-magnitude-error``): magnitude error of thresholded
  (5 sigma), weighted-sum photometry of stars of V 0-4 (Table 5.2's camera), with the seed's
  literal eq. 3.4 signal scale and with our physical one.

Usage::

    python benchmarks/simulate_benchmark.py [--repeats 15] [--quick] [--no-save] [--no-seed-tables]
        [--workers 2 | --sync] [--out DIR]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))

from seed_campaign import add_run_arguments, out_for, print_references, run_spec, spec_text  # noqa: E402

from startrack.camera import Camera  # noqa: E402
from startrack.simulate import (  # noqa: E402
    SkyBackground,
    get_sensor_preset,
    random_attitude,
    render_stars,
    simulate_frame,
)
from startrack.simulate._noise import NoiseModel  # noqa: E402
from startrack.units import DEG  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
CAMERA = Camera.from_fov(1024, 1024, 15.0)
SKY = SkyBackground(mag_arcsec2=21.5, stray_e_s_px=5.0)
EFFECTS = {"hot_pixel_fraction": 1e-4, "dead_pixel_fraction": 1e-4}
PATTERN = {"prnu_rms": 0.01, "dsnu_rms": 0.2}
ALL = NoiseModel()
SIGNAL_ONLY = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False,
                         background=False, prnu=False, dsnu=False, hot_pixels=False, dead_pixels=False)


def sensor_with(exposure_s: float, **detector):
    base = get_sensor_preset("generic-cmos").with_exposure(exposure_s)
    return dataclasses.replace(base, detector=dataclasses.replace(base.detector, **detector))


def median_ms(func, repeats: int) -> float:
    func()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        func()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def random_stars(n: int, rng: np.random.Generator, rot):
    x = rng.uniform(10, CAMERA.width - 10, n)
    y = rng.uniform(10, CAMERA.height - 10, n)
    vectors = rot.inv().apply(CAMERA.pixel_to_vector(x, y))
    return vectors, rng.uniform(3.0, 7.0, n), np.arange(n)


# ---------------------------------------------------------------- the plain loops
def loop_signal(truth, sensor) -> np.ndarray:
    """Star electrons per pixel: star by star, sub-step by sub-step (the attitude at each from the
    constant rate), stamp pixel by stamp pixel."""
    from startrack.simulate._scene import psf_radius_px

    sigma2 = math.sqrt(2.0) * sensor.psf_sigma_px
    radius = psf_radius_px(CAMERA, sensor)
    n = truth.substeps
    image = np.zeros((CAMERA.height, CAMERA.width)).tolist()
    for k in range(len(truth)):
        for s in range(n):
            t = truth.exposure_s * ((s + 0.5) / n - 0.5)
            rot = Rotation.from_rotvec(-t * truth.rate_cam_rad_s) * truth.rot_cam_from_icrs
            x, y = CAMERA.vector_to_pixel(rot.apply(truth.vectors_icrs[k]))
            xc, yc = math.floor(x + 0.5), math.floor(y + 0.5)
            for row in range(max(0, yc - radius), min(CAMERA.height, yc + radius + 1)):
                fy = 0.5 * (math.erf((row + 0.5 - y) / sigma2) - math.erf((row - 0.5 - y) / sigma2))
                for col in range(max(0, xc - radius), min(CAMERA.width, xc + radius + 1)):
                    fx = 0.5 * (math.erf((col + 0.5 - x) / sigma2) - math.erf((col - 0.5 - x) / sigma2))
                    image[row][col] += truth.electrons[k] / n * fx * fy
    return np.array(image)


def loop_read_out(signal: np.ndarray, sensor, background: float, rng: np.random.Generator) -> np.ndarray:
    """Shot noise, full well, read noise, gain, bias, quantisation, pixel by pixel (no fixed pattern)."""
    det = sensor.detector
    out = np.empty(signal.shape, dtype=np.uint16)
    level = background + sensor.dark_e
    for row in range(signal.shape[0]):
        for col in range(signal.shape[1]):
            charge = min(float(rng.poisson(signal[row, col] + level)), det.full_well_e)
            adu = (charge + det.read_noise_e * rng.standard_normal()) / det.gain_e_per_adu + det.bias_adu
            out[row, col] = min(max(math.floor(adu + 0.5), 0), det.max_adu)
    return out


# ---------------------------------------------------------------- timings
def timings(repeats: int, with_loop: bool) -> list[dict]:
    rng = np.random.default_rng(1)
    rot = random_attitude(rng)
    stars = random_stars(30, rng, rot)
    still, streak = sensor_with(0.2, **EFFECTS), sensor_with(0.5, **EFFECTS)
    pattern = sensor_with(0.2, **EFFECTS, **PATTERN)
    rate = (1.0 * DEG, 0.0, 0.0)
    catalog = random_attitude(3)
    frames = [
        ("point, 30 stars, all noise", still, lambda noise=ALL: render_stars(
            CAMERA, rot, *stars, sensor=still, sky_background=SKY, rng=2, noise=noise)),
        ("point, 30 stars, + PRNU, DSNU", pattern, lambda noise=ALL: render_stars(
            CAMERA, rot, *stars, sensor=pattern, sky_background=SKY, rng=2, noise=noise)),
        ("streak 0.5 s, 1 deg/s, 30 stars", streak, lambda noise=ALL: render_stars(
            CAMERA, rot, *stars, sensor=streak, rate_rad_s=rate, sky_background=SKY, rng=4, noise=noise)),
        ("streak 0.5 s, 1 deg/s, V <= 7.5", streak, lambda noise=ALL: simulate_frame(
            CAMERA, catalog, max_mag=7.5, sensor=streak, rate_rad_s=rate, sky_background=SKY, rng=4,
            noise=noise)),
    ]
    rows = []
    for label, sensor, frame in frames:
        row = {"frame": label, "median_ms": median_ms(frame, repeats), "stars": len(frame().truth)}
        if with_loop and "V <=" not in label:
            row.update(_loop_row(frame, sensor, row["median_ms"]))
        rows.append(row)
    return rows


def _loop_row(frame, sensor, ms: float) -> dict:
    sim = frame()
    t0 = time.perf_counter()
    signal = loop_signal(sim.truth, sensor)
    loop_read_out(signal, sensor, SKY.electrons(CAMERA, sensor), np.random.default_rng(0))
    loop_ms = 1e3 * (time.perf_counter() - t0)
    ours = frame(noise=SIGNAL_ONLY).image * sensor.detector.gain_e_per_adu
    return {"loop_ms": loop_ms, "ratio": loop_ms / ms,
            "loop_max_diff_rel": float(np.abs(ours - signal).max() / ours.max())}


# ---------------------------------------------------------------- seed reproductions
SEED_SPECS = ("samaan2002-table1-smear-rate", "huffman2006-table5.1-star-availability",
              "huffman2006-table5.3-magnitude-error")
QUICK_TRIALS = {"samaan2002-table1-smear-rate": 2, "huffman2006-table5.1-star-availability": 4000,
                "huffman2006-table5.3-magnitude-error": 20}
"""Trials per cell with --quick (a 3.2 deg lattice for Table 5.1: its limits come out lower)."""


def seed_tables(args: argparse.Namespace) -> dict[str, str]:
    """Run the seed-table specs and print their reference tables; returns name -> the tables' text."""
    out = {}
    for name in SEED_SPECS:
        text = spec_text(name, trials=QUICK_TRIALS[name] if args.quick else None)
        _, folder, _ = run_spec(text, out_for(args, name), args.workers, args.sync)
        out[name] = print_references(folder)
        print()
    return out


# ---------------------------------------------------------------- output
def print_results(results: dict) -> None:
    print("\nsimulator speed (median ms; 1024 x 1024, 15 deg, generic-cmos)")
    print(f"{'frame':<34}{'stars':>6}{'startrack':>10}{'plain loop':>12}{'ratio':>8}{'max diff':>12}")
    for r in results["timings"]:
        loop = f"{r['loop_ms']:.0f}" if "loop_ms" in r else "-"
        ratio = f"{r['ratio']:.0f}x" if "ratio" in r else "-"
        diff = f"{r['loop_max_diff_rel']:.1e}" if "loop_max_diff_rel" in r else "-"
        print(f"{r['frame']:<34}{r['stars']:>6}{r['median_ms']:>10.1f}{loop:>12}{ratio:>8}{diff:>12}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=15, help="timed runs per frame (default 15)")
    parser.add_argument("--quick", action="store_true", help="no plain loops; seed tables with few trials")
    parser.add_argument("--no-save", action="store_true", help="do not write benchmarks/results/simulate-*.json")
    parser.add_argument("--no-seed-tables", action="store_true", help="only the speed part")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    results = {"timings": timings(args.repeats, not args.quick)}
    print_results(results)
    if not args.no_seed_tables:
        print()
        results["seed_tables"] = seed_tables(args)
    if not args.no_save:
        RESULTS.mkdir(exist_ok=True)
        path = RESULTS / f"simulate-{time.strftime('%Y%m%d-%H%M%S')}.json"
        path.write_text(json.dumps(results, indent=1))
        print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
