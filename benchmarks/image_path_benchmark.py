"""The whole image path, end to end: read a 1024 x 1024 16-bit frame, detect the stars, solve.

Seeded frames are simulated at uniformly random attitudes (``startrack.simulate.simulate_frame``
with its noise model) and written to a temporary folder in each ``--formats`` format: a 16-bit
PNG (compressed: its decoding is timed and printed apart), an uncompressed FITS file
(``startrack.io.write_fits``, BITPIX 16) and a raw array (the uint16 pixels as they are in
memory, ``ndarray.tofile``, read back by ``np.fromfile``). Each file is solved with
``startrack.solve_image`` (the path for PNG and FITS, the array read from the raw file),
timed around reading and that call by the wall clock (``time.perf_counter``), or with
``--clock cpu`` by the CPU time of the process (``time.process_time``, which leaves out the time
the process waits for a core on a shared machine); simulation and writing are not timed. One
untimed warm-up call runs first (it loads the pattern database and the compiled loops; its time
is printed apart). A solve succeeds when its attitude is within 5 pixel angles
of the truth (see :mod:`scoring`). Targets on the 2-core reference machine: median under 50 ms
for PNG; for an uncompressed frame (FITS or raw array) 6 ms (issue 20, item 5).

The sensor is the Huffman 2006 FAR-MST one (``get_sensor_preset("far-mst")``) with a 1.0 s exposure
and a 1.5 px PSF, and stars to V 7.0 are rendered at epoch 2025.0 (also given to the solver):
that gives 25-70 detections per frame at a 15 deg FOV. (With the preset's 0.1 s and 2.5 px,
only one or two stars clear the detection threshold of a 1024 px, 15 deg frame.)

The same files are then run through the stages one by one (``startrack.io.read_image``,
``startrack.detect.detect``, ``solve_stars``), each timed, to show where the time goes.

Usage::

    python benchmarks/image_path_benchmark.py [--frames 50] [--seed 1] [--fov-deg 15]
        [--formats png fits raw] [--clock wall|cpu]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from process_clocks import CLOCKS, add_clock_option, clock_name  # noqa: E402

from startrack import solve_image, solve_stars  # noqa: E402
from startrack.analysis._scoring import TOLERANCE_PIXELS, attitude_errors_rad, roll_weight, summarize, tolerance_rad  # noqa: E402
from startrack.camera import Camera  # noqa: E402
from startrack.frames import random_rotations  # noqa: E402

TARGET_MEDIAN_MS = {"png": 50.0, "fits": 6.0, "raw": 6.0}
FORMATS = ("png", "fits", "raw")
EPOCH_JYEAR = 2025.0
"""Epoch of the simulated star positions, given to the solver too."""


def benchmark_sensor(exposure_s: float, psf_sigma_px: float):
    """The FAR-MST sensor of Huffman 2006 with another exposure time and PSF width."""
    from startrack.simulate import get_sensor_preset

    base = get_sensor_preset("far-mst").with_exposure(exposure_s)
    return replace(base, optics=replace(base.optics, psf_sigma_px=psf_sigma_px))


def write_frames(camera: Camera, args: argparse.Namespace, folder: Path) -> list:
    """Simulate ``args.frames`` frames and write each in every format of ``args.formats``;
    return (paths by format, truth) pairs."""
    from startrack.io import write_fits, write_png
    from startrack.simulate import simulate_frame

    rng = np.random.default_rng(args.seed)
    sensor = benchmark_sensor(args.exposure_s, args.psf_sigma_px)
    frames = []
    for i, rot in enumerate(random_rotations(args.frames, rng=rng)):
        sim = simulate_frame(camera, rot, rng=rng, sensor=sensor, max_mag=args.max_mag,
                             epoch_jyear=EPOCH_JYEAR)
        image = np.clip(np.round(sim.image), 0, 65535).astype(np.uint16)
        paths = {}
        for fmt in args.formats:
            path = folder / f"frame{i:04d}.{fmt}"
            if fmt == "png":
                write_png(path, image)
            elif fmt == "fits":
                write_fits(path, image)
            else:
                image.tofile(path)
            paths[fmt] = path
        frames.append((paths, rot))
    return frames


def read_pixels(path: Path, fmt: str, shape: tuple[int, int]) -> np.ndarray:
    """The frame's pixels: ``startrack.io.read_image`` for a PNG or FITS file, ``np.fromfile``
    for a raw array of ``shape`` uint16."""
    if fmt == "raw":
        return np.fromfile(path, dtype=np.uint16).reshape(shape)
    from startrack.io import read_image

    return read_image(path).data


def solve_file(path: Path, fmt: str, shape: tuple[int, int], fov_deg: float):
    """Read and solve one file: ``solve_image`` on the path (PNG, FITS) or on the raw array."""
    source = read_pixels(path, fmt, shape) if fmt == "raw" else path
    return solve_image(source, fov_deg=fov_deg, epoch=EPOCH_JYEAR)


def time_solves(frames: list, fmt: str, shape: tuple[int, int], fov_deg: float, clock: str = "wall"
                ) -> tuple[list, np.ndarray, float]:
    """Solve each file; return the attitudes (None when unsolved), times (s) and the warm-up
    time (s), by ``clock`` (:data:`CLOCKS`)."""
    now = CLOCKS[clock]
    t0 = now()
    solve_file(frames[0][0][fmt], fmt, shape, fov_deg)
    warmup_s = now() - t0
    estimates, times = [], np.zeros(len(frames))
    for i, (paths, _) in enumerate(frames):
        t0 = now()
        sol = solve_file(paths[fmt], fmt, shape, fov_deg)
        times[i] = now() - t0
        estimates.append(sol.rot_cam_from_icrs if sol.status else None)
    return estimates, times, warmup_s


def time_stages(frames: list, fmt: str, shape: tuple[int, int], fov_deg: float, clock: str = "wall"
                ) -> tuple[dict[str, np.ndarray], list, np.ndarray]:
    """Per-file times (s, by ``clock``) of reading, detecting and solving called one by one; the
    attitudes (None when unsolved) and the number of detections per file."""
    from startrack.detect import detect

    now = CLOCKS[clock]
    times = {k: np.zeros(len(frames)) for k in ("read", "detect", "solve")}
    estimates, n_det = [], np.zeros(len(frames), dtype=int)
    for i, (paths, _) in enumerate(frames):
        t0 = now()
        data = read_pixels(paths[fmt], fmt, shape)
        t1 = now()
        det = detect(data)
        t2 = now()
        sol = solve_stars(det.x, det.y, flux=det.flux, width=data.shape[1],
                          height=data.shape[0], fov_deg=fov_deg, epoch=EPOCH_JYEAR)
        t3 = now()
        times["read"][i], times["detect"][i], times["solve"][i] = t1 - t0, t2 - t1, t3 - t2
        estimates.append(sol.rot_cam_from_icrs if sol.status else None)
        n_det[i] = len(det)
    return times, estimates, n_det


def print_end_to_end(frames: list, fmt: str, camera: Camera, args: argparse.Namespace) -> None:
    shape = (args.size, args.size)
    estimates, times, warmup_s = time_solves(frames, fmt, shape, args.fov_deg, args.clock)
    solved = np.array([e is not None for e in estimates])
    err = attitude_errors_rad([rot for _, rot in frames], estimates, roll_weight(camera))
    s = summarize(solved, err, times, tolerance_rad(camera))
    target = TARGET_MEDIAN_MS[fmt]
    verdict = "meets" if s["median_ms"] <= target else "misses"
    clock = clock_name(args.clock)
    print(f"\nimage path (read {fmt.upper()}, detect, solve), {args.size} x {args.size} px, "
          f"FOV {args.fov_deg:g} deg, {s['n']} frames ({int(solved.sum())} solved), by the {clock}")
    print(f"  median {s['median_ms']:.1f} ms, p95 {s['p95_ms']:.1f} ms "
          f"({verdict} the {target:g} ms median target); first call {warmup_s:.2f} s")
    print(f"  success {s['success_rate']:.1%}, false solves {s['false_rate']:.1%} "
          f"(within {TOLERANCE_PIXELS:g} pixel angles; "
          f"median error {s['median_err_arcsec']:.1f} arcsec)")


def print_stages(frames: list, fmt: str, camera: Camera, args: argparse.Namespace) -> None:
    stages, estimates, n_det = time_stages(frames, fmt, (args.size, args.size), args.fov_deg, args.clock)
    total = sum(stages.values())
    err = attitude_errors_rad([rot for _, rot in frames], estimates, roll_weight(camera))
    solved = np.array([e is not None for e in estimates])
    s = summarize(solved, err, total, tolerance_rad(camera))
    reading = "read (PNG decoding)" if fmt == "png" else "read"
    parts = ", ".join(f"{reading if k == 'read' else k} {np.median(v) * 1e3:.2f}" for k, v in stages.items())
    print(f"  stage by stage, median ms: {parts}; sum: median {s['median_ms']:.1f}, "
          f"p95 {s['p95_ms']:.1f}")
    if fmt == "png":
        rest = stages["detect"] + stages["solve"]
        print(f"  without the PNG decoding (detect + solve): median {np.median(rest) * 1e3:.1f} ms")
    print(f"  stage by stage: success {s['success_rate']:.1%}, false {s['false_rate']:.1%}, "
          f"detections per frame median {np.median(n_det):.0f} (5-95 %: "
          f"{np.percentile(n_det, 5):.0f}-{np.percentile(n_det, 95):.0f})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=50)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--fov-deg", type=float, default=15.0)
    parser.add_argument("--size", type=int, default=1024, help="image width and height (px)")
    parser.add_argument("--max-mag", type=float, default=7.0, help="faintest star rendered (V)")
    parser.add_argument("--exposure-s", type=float, default=1.0)
    parser.add_argument("--psf-sigma-px", type=float, default=1.5)
    parser.add_argument("--formats", nargs="+", choices=FORMATS, default=list(FORMATS),
                        help="file formats to time (default: all)")
    add_clock_option(parser)
    args = parser.parse_args(argv)
    camera = Camera.from_fov(args.size, args.size, args.fov_deg)
    with tempfile.TemporaryDirectory(prefix="startrack-imgbench-") as tmp:
        print(f"simulating {args.frames} frames of {args.size} x {args.size} px, "
              f"FOV {args.fov_deg:g} deg", file=sys.stderr, flush=True)
        frames = write_frames(camera, args, Path(tmp))
        print(f"load average {os.getloadavg()[0]:.2f}")
        for fmt in args.formats:
            print_end_to_end(frames, fmt, camera, args)
            print_stages(frames, fmt, camera, args)
        print(f"load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
