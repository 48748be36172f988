"""The star-camera simulator: speed, against a plain per-pixel loop, and the seed reproductions.

Timings (``time.perf_counter``, median of ``--repeats`` runs after one warm-up, on 1024 x 1024
frames of a 15 deg pinhole camera with the ``generic-cmos`` sensor):

- **point frame**: 30 stars at random positions (``render_stars``) with every noise source on:
  shot noise, dark current, read noise, bias, gain, 12-bit quantisation, full well, a 21.5 mag
  arcsec^-2 sky, stray light, hot and dead pixels; target under 30 ms;
- the same **with PRNU and DSNU** (every pixel then has its own expectation and is drawn one by
  one: the slow path of :mod:`startrack.simulate.noise`);
- **streaked frame**: 0.5 s at 1 deg/s, the Hipparcos sky to V 7.5 (about 190 stars), every noise
  source; target under 150 ms median; and the same with only 30 stars.

Each simulated frame is also rendered by a plain Python loop (pixel by pixel for the point frame;
sample by sample and stamp pixel by stamp pixel for the streak, then pixel by pixel for the noise)
on the same inputs (shot, dark, read noise, gain, bias, quantisation, full well; the loop leaves
out the fixed pattern); the table prints the ratio, and the largest difference of the loop's
noise-free star image from the simulator's, relative to the brightest pixel.

Seed reproductions (documented in docs/simulation.md):

- seed 004 Table 1: the largest rate for negligible smear (0.1 px) with StarNav I;
- seed 000 Table 5.1: the magnitude limit that guarantees 4 or 6 stars in every field (1 deg sky
  grid), cone and square fields, with Hipparcos-2;
- seed 000 Table 5.3: magnitude error of thresholded (5 sigma), weighted-sum photometry of stars
  of V 0-4 (Table 5.2's camera: a = pi 0.01^2 m^2, gain 10, t = 0.1 s, PSF width 10 px, dark
  41 e-, read 40 e-), with the seed's literal eq. 3.4 signal scale and with our physical one.

Usage::

    python benchmarks/simulate_benchmark.py [--repeats 15] [--quick] [--no-save]
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
from scipy import ndimage
from scipy.spatial.transform import Rotation

from startrack import get_preset
from startrack.camera import Camera
from startrack.simulate import (
    SkyBackground,
    get_sensor_preset,
    magnitude_from_electrons,
    max_rate_rad_s,
    random_attitude,
    render_stars,
    simulate_frame,
)
from startrack.simulate.noise import NoiseModel
from startrack.simulate.starcount import limiting_mag_for_min_stars
from startrack.units import DEG

RESULTS = Path(__file__).resolve().parent / "results"
CAMERA = Camera.from_fov(1024, 1024, 15.0)
SKY = SkyBackground(mag_arcsec2=21.5, stray_e_s_px=5.0)
EFFECTS = {"hot_pixel_fraction": 1e-4, "dead_pixel_fraction": 1e-4}
PATTERN = {"prnu_rms": 0.01, "dsnu_rms": 0.2}
ALL = NoiseModel()
SIGNAL_ONLY = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False,
                         background=False, prnu=False, dsnu=False, hot_pixels=False, dead_pixels=False)
SEED_NOISE = NoiseModel(saturate=False, quantize=False)
"""Seed 000's images are Matlab doubles: no full well, no ADC range (a V = 0 star would saturate)."""
TABLE_1 = {10: 0.156, 20: 0.078, 30: 0.052, 50: 0.0313}
TABLE_5_1 = {25: (3.9, 4.3), 30: (3.6, 3.9), 35: (3.4, 3.6), 40: (3.3, 3.4), 45: (3.1, 3.3)}
TABLE_5_3 = {0: (0.0309, 0.0427), 1: (0.0311, 0.0324), 2: (0.0353, 0.0419), 3: (0.0552, 0.0414),
             4: (0.1362, 0.0685)}


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
    from startrack.simulate.scene import psf_radius_px

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
def table_1() -> list[dict]:
    camera = get_preset("starnav-i")
    return [{"exposure_ms": t, "seed_deg_s": v, "ours_deg_s": max_rate_rad_s(camera, t * 1e-3, 0.1) / DEG}
            for t, v in TABLE_1.items()]


def table_5_1(step_deg: float) -> list[dict]:
    """Seed 000 Table 5.1 by the seed's method (the worst pointing of a sky grid), and the mean
    reading: the limit at which the *average* field holds n stars."""
    from startrack.catalog import load_catalog

    cat = load_catalog().brighter_than(6.5)
    vectors, mags = cat.vectors(2000.0), np.sort(np.asarray(cat.v_mag, dtype=float))
    rows = []
    for fov, seed in TABLE_5_1.items():
        row = {"fov_deg": fov, "seed_min4": seed[0], "seed_min6": seed[1]}
        cone_fraction = (1.0 - math.cos(math.radians(fov) / 2.0)) / 2.0
        for n in (4, 6):
            for shape in ("circle", "square"):
                row[f"{shape}_min{n}"] = limiting_mag_for_min_stars(vectors, np.asarray(cat.v_mag, float), fov, n,
                                                                    shape, step_deg)
            row[f"circle_mean{n}"] = float(mags[math.ceil(n / cone_fraction) - 1])
        rows.append(row)
    return rows


def table_5_3(stars_per_mag: int, scale: str) -> list[dict]:
    """Seed 000 Table 5.2 / 5.3: 20 stars a frame, 5 sigma threshold, weighted-sum brightness."""
    preset = "far-mst-seed-eq34" if scale == "seed" else "far-mst"
    base = get_sensor_preset(preset)
    sensor = dataclasses.replace(base, optics=dataclasses.replace(base.optics, aperture_area_m2=math.pi * 0.01**2),
                                 detector=dataclasses.replace(base.detector, read_noise_e=40.0,
                                                              dark_current_e_s=410.0))
    camera = get_preset("far-mst")
    det = sensor.detector
    threshold_adu = 5.0 * math.sqrt(sensor.dark_e + det.read_noise_e**2) / det.gain_e_per_adu
    rng = np.random.default_rng(53)
    rows = []
    for mag in TABLE_5_3:
        diffs, found, runs = [], 0, 0
        while len(diffs) < stars_per_mag and runs < 4 * stars_per_mag // 20 + 4:
            runs += 1
            rot = random_attitude(rng)
            x, y = rng.uniform(20, camera.width - 20, 20), rng.uniform(20, camera.height - 20, 20)
            sim = render_stars(camera, rot, rot.inv().apply(camera.pixel_to_vector(x, y)), np.full(20, float(mag)),
                               np.arange(20), sensor=sensor, rng=rng, noise=SEED_NOISE)
            est = _weighted_sum_mags(sim, sensor, threshold_adu)
            found += int(np.isfinite(est).sum())
            if np.all(np.isfinite(est)):  # the seed kept only runs where all 20 were centroided
                diffs.extend(est - mag)
        diffs = np.array(diffs)
        rows.append({"mag": mag, "seed_mean": TABLE_5_3[mag][0], "seed_std": TABLE_5_3[mag][1],
                     "mean_diff": float(diffs.mean()) if diffs.size else math.nan,
                     "median_diff": float(np.median(diffs)) if diffs.size else math.nan,
                     "std_diff": float(diffs.std(ddof=1)) if diffs.size > 1 else math.nan,
                     "kept_stars": int(diffs.size), "detected_fraction": found / (20 * runs)})
    return rows


def _weighted_sum_mags(sim, sensor, threshold_adu: float) -> np.ndarray:
    """Magnitude of each true star from the sum of its 8-connected above-threshold cluster (NaN when
    the star is not detected or shares its cluster with another star: the seed's centroider then
    finds fewer than 20 stars and the run is left out)."""
    det = sensor.detector
    dark_subtracted = sim.image.astype(float) - (det.bias_adu + sensor.dark_e / det.gain_e_per_adu)
    labels, _ = ndimage.label(dark_subtracted > threshold_adu, structure=np.ones((3, 3)))
    sums = ndimage.sum_labels(dark_subtracted, labels, index=np.arange(labels.max() + 1))
    rows = np.clip(np.round(sim.truth.y).astype(int), 0, labels.shape[0] - 1)
    cols = np.clip(np.round(sim.truth.x).astype(int), 0, labels.shape[1] - 1)
    lab = labels[rows, cols]
    shared = np.bincount(lab, minlength=labels.max() + 1)[lab] > 1  # two stars in one cluster: one centroid
    electrons = np.where((lab > 0) & ~shared, sums[lab] * det.gain_e_per_adu, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(electrons > 0, magnitude_from_electrons(electrons, sensor), np.nan)


# ---------------------------------------------------------------- output
def print_results(results: dict) -> None:
    print("\nsimulator speed (median ms; 1024 x 1024, 15 deg, generic-cmos)")
    print(f"{'frame':<34}{'stars':>6}{'startrack':>10}{'plain loop':>12}{'ratio':>8}{'max diff':>12}")
    for r in results["timings"]:
        loop = f"{r['loop_ms']:.0f}" if "loop_ms" in r else "-"
        ratio = f"{r['ratio']:.0f}x" if "ratio" in r else "-"
        diff = f"{r['loop_max_diff_rel']:.1e}" if "loop_max_diff_rel" in r else "-"
        print(f"{r['frame']:<34}{r['stars']:>6}{r['median_ms']:>10.1f}{loop:>12}{ratio:>8}{diff:>12}")
    print("\nseed 004 Table 1: max rate for 0.1 px of smear (StarNav I, 512 px, 8 deg)")
    for r in results["table_1"]:
        print(f"  t = {r['exposure_ms']:>2} ms   seed {r['seed_deg_s']:.4f}   ours {r['ours_deg_s']:.4f} deg/s")
    print("\nseed 000 Table 5.1: V limit for at least 4 / 6 stars in every field (1 deg grid)")
    print(f"{'FOV':>5}{'seed 4':>8}{'seed 6':>8}{'cone 4':>8}{'cone 6':>8}{'square 4':>10}{'square 6':>10}"
          f"{'mean 4':>8}{'mean 6':>8}")
    for r in results["table_5_1"]:
        print(f"{r['fov_deg']:>5}{r['seed_min4']:>8.1f}{r['seed_min6']:>8.1f}{r['circle_min4']:>8.2f}"
              f"{r['circle_min6']:>8.2f}{r['square_min4']:>10.2f}{r['square_min6']:>10.2f}"
              f"{r['circle_mean4']:>8.2f}{r['circle_mean6']:>8.2f}")
    for scale in ("seed", "physical"):
        print(f"\nseed 000 Table 5.3: magnitude error, thresholded weighted sum ({scale} signal scale)")
        print(f"{'V':>3}{'seed mean':>11}{'seed std':>10}{'ours mean':>11}{'ours std':>10}{'median':>9}"
              f"{'kept':>6}{'found':>7}")
        for r in results[f"table_5_3_{scale}"]:
            print(f"{r['mag']:>3}{r['seed_mean']:>11.4f}{r['seed_std']:>10.4f}{r['mean_diff']:>11.4f}"
                  f"{r['std_diff']:>10.4f}{r['median_diff']:>9.4f}{r['kept_stars']:>6}{r['detected_fraction']:>7.0%}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=15, help="timed runs per frame (default 15)")
    parser.add_argument("--quick", action="store_true", help="no plain loops, coarse grids, fewer stars")
    parser.add_argument("--no-save", action="store_true", help="do not write benchmarks/results/simulate-*.json")
    args = parser.parse_args(argv)
    results = {"timings": timings(args.repeats, not args.quick), "table_1": table_1(),
               "table_5_1": table_5_1(5.0 if args.quick else 1.0)}
    for scale in ("seed", "physical"):
        results[f"table_5_3_{scale}"] = table_5_3(100 if args.quick else 500, scale)
    print_results(results)
    if not args.no_save:
        RESULTS.mkdir(exist_ok=True)
        path = RESULTS / f"simulate-{time.strftime('%Y%m%d-%H%M%S')}.json"
        path.write_text(json.dumps(results, indent=1))
        print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
