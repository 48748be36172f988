"""Calibration accuracy: the Fowler 2013 cameras from simulated *images*, and the real images.

1. Simulated frames of the Aptina MT9P031 and Droid X2 (Fowler 2013's published focal lengths,
   principal points and distortion) at random attitudes: rendered, detected and centroided by the
   ordinary pipeline; detections are paired with the rendered stars within 2 px (identification is
   not what is measured here) and the camera is calibrated from 1 frame and from 20, starting from
   the nominal focal length (1 % off), a centred principal point and no distortion. Printed: focal
   length error (%), principal point error (px), distortion error over the frame (RMS px), residual.
2. The real images of ../shared/realdata: self-calibration (solve, calibrate, re-solve) from a
   5-35 deg FOV range; the pinhole and the calibrated residual on the same stars, and the difference
   of our WCS to astrometry.net's across the whole frame.

Run: ``.venv/bin/python benchmarks/calibration_benchmark.py [--frames 20] [--seed 1]``
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from startrack.calibrate._lens_models import distortion_field_px
from startrack.calibrate._selfcal import self_calibrate
from startrack.calibrate._stars import CalibrationFrame, calibrate_from_stars
from startrack.camera import Camera, get_preset
from startrack.detect import StarDetector
from startrack.frames import random_rotations
from startrack.io._wcs import read_wcs, solution_wcs
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
ALL = ("f", "aspect", "cx", "cy", "k1", "k2", "k3", "p1", "p2")


def _frame(camera: Camera, rot: Rotation, rng: np.random.Generator) -> CalibrationFrame:
    sim = simulate_frame(camera, rot, max_mag=6.5, sensor=get_sensor_preset("generic-cmos"), rng=rng)
    det = StarDetector().detect(sim.image)
    truth = sim.truth
    dist, idx = cKDTree(np.column_stack([truth.x, truth.y])).query(np.column_stack([det.x, det.y]))
    ok = dist < 2.0
    start = Rotation.from_rotvec(rng.normal(0, 0.05 * DEG, 3)) * rot
    return CalibrationFrame(det.x[ok], det.y[ok], truth.vectors_icrs[idx[ok]], start)


def _errors(cam: Camera, truth: Camera) -> tuple[float, float, float]:
    _, _, d1 = distortion_field_px(cam)
    _, _, d2 = distortion_field_px(truth)
    return (100 * (cam.fx / truth.fx - 1), float(np.hypot(cam.cx - truth.cx, cam.cy - truth.cy)),
            float(np.sqrt(np.mean(np.sum((d1 - d2) ** 2, axis=1)))))


def simulated(n_frames: int, seed: int) -> None:
    print("camera           frames stars   df/f %   dpp px  dist rms px  resid px  pruned          time s")
    for preset in ("aptina-mt9p031", "droid-x2"):
        truth = get_preset(preset)
        rng = np.random.default_rng(seed)
        frames = [_frame(truth, rot, rng) for rot in random_rotations(n_frames, rng=rng)]
        start = Camera(width=truth.width, height=truth.height, fx=truth.fx * 1.01)
        for n in (1, n_frames):
            t0 = time.perf_counter()
            res = calibrate_from_stars(frames[:n], start, fit=ALL)
            df, dpp, drms = _errors(res.camera, truth)
            stars = sum(len(f) for f in frames[:n])
            print(f"{preset:16s} {n:6d} {stars:5d} {df:+8.4f} {dpp:8.3f} {drms:12.3f} {res.rms_px:9.3f}  "
                  f"{','.join(res.pruned):15s} {time.perf_counter() - t0:6.2f}")


def real() -> None:
    if not (REALDATA / "truth.csv").is_file():
        print(f"(no real images: {REALDATA} is absent)")
        return
    print("\nimage            solve\"  stars  pinhole px (arcsec)  calibrated px (arcsec)  "
          "WCS diff rms / max px  pruned")
    with open(REALDATA / "truth.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    for row in rows:
        sc = self_calibrate(REALDATA / row["set"] / row["file"], fov_range_deg=(5.0, 35.0))
        truth = read_wcs(REALDATA / row["set"] / "truth" / (row["file"].rsplit(".", 1)[0] + ".wcs"))
        ours = solution_wcs(sc.solution.rot_cam_from_icrs, sc.solution.camera)
        w, h = int(row["width"]), int(row["height"])
        gx, gy = np.meshgrid(np.linspace(0, w - 1, 25), np.linspace(0, h - 1, 25))
        sep = ours.pixel_to_world(gx.ravel(), gy.ravel()).separation(truth.pixel_to_world(gx.ravel(), gy.ravel()))
        sep_px = sep.arcsec / float(row["pixscale_arcsec"])
        print(f"{row['file']:16s} {sc.first_solve_rms_arcsec:6.1f} {sc.n_calibrated:5d}  "
              f"{sc.pinhole_rms_px:6.3f} ({sc.pinhole_rms_arcsec:5.1f})"
              f"        {sc.calibrated_rms_px:6.3f} ({sc.calibrated_rms_arcsec:5.1f})"
              f"          {np.sqrt(np.mean(sep_px**2)):5.2f} / {sep_px.max():5.2f}       "
              f"{','.join(sc.calibration.pruned)}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    simulated(args.frames, args.seed)
    real()
    return 0


if __name__ == "__main__":
    sys.exit(main())
