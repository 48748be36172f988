"""Detection speed and accuracy beside SEP and photutils' DAOStarFinder, on the same frames.

Also the default without its full-resolution pass (``fine_sigma=None``, the detector of
before issue 17), for what that pass costs. Frames: 1024 x 1024 uint16, 30 stars each (PSF sigma
1.5 px, integrated SNR log-uniform in
10-300, 100 e- sky, 5 e- read noise; ``detect_frames.py``). Per method: the median time per frame
(median over ``--repeats`` runs of each frame, then over frames), the completeness and the false
detections per frame against the truth (2 px), the RMS centroid error over the stars it found
and over the stars every method found (the same stars for all). The peers run in their own
environment (``peers/detect_env.py``) in a subprocess reading the same frames from an ``.npz``.
Also: each method's time as a multiple of SEP's (``x SEP``), the memory-bandwidth floor of the
default detector (the bytes its whole-frame passes read and write, :func:`frame_passes`, at the
bandwidth of a numpy copy of the frame), the predictive pass over 20 windows, and with
``--huge`` the peak memory of a 20,000 x 20,000 frame (``tracemalloc``). Times are wall-clock
times, or with ``--clock cpu`` the CPU time of the process (``time.process_time``, for every
method), which leaves out the time the process waits for a core on a shared machine.

    .venv/bin/python benchmarks/detect_speed.py [--frames 5] [--repeats 15] [--no-peers] [--huge]
        [--clock wall|cpu]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_frames import grid_positions, match, render_frame  # noqa: E402
from peers.detect_env import run_peers  # noqa: E402
from process_clocks import CLOCKS, add_clock_option, clock_name  # noqa: E402

from startrack.detect import StarDetector  # noqa: E402
from startrack.detect import _crb as crb
from startrack.simulate import render_gaussian_psf  # noqa: E402

SHAPE = (1024, 1024)
PSF_SIGMA_PX = 1.5
N_STARS = 30


def _without_fine_pass() -> StarDetector:
    """The default detector without its full-resolution pass (``fine_sigma=None``): the cost of
    that pass, which finds sharp and blended stars that these frames do not have."""
    return StarDetector(fine_sigma=None)


def make_frames(n: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(n):
        x, y = grid_positions(SHAPE, 150, rng, margin=40)
        pick = rng.choice(x.size, N_STARS, replace=False)
        snr = np.exp(rng.uniform(np.log(10.0), np.log(300.0), N_STARS))
        flux = crb.flux_for_snr(snr, PSF_SIGMA_PX, 100.0, 5.0)
        frames.append(render_frame(SHAPE, x[pick], y[pick], flux, PSF_SIGMA_PX, rng))
    return frames


def time_ours(detector: StarDetector, frames: list, repeats: int, clock: str = "wall"
              ) -> tuple[list, np.ndarray, np.ndarray]:
    """Detect each frame ``repeats`` times (after one untimed run), timed by ``clock``
    (:data:`CLOCKS`); return the last run's (x, y) per frame and the median and fastest time (s)
    per frame, each of shape (n_frames,)."""
    now = CLOCKS[clock]
    results, times, best = [], [], []
    for frame in frames:
        detector.detect(frame.image)  # warm-up
        samples = []
        for _ in range(repeats):
            t0 = now()
            det = detector.detect(frame.image)
            samples.append(now() - t0)
        results.append((det.x, det.y))
        times.append(np.median(samples))
        best.append(np.min(samples))
    return results, np.array(times), np.array(best)


def score(frames: list, results: list) -> tuple[float, float, list]:
    """Completeness, false per frame, and per frame the error of each true star (NaN if
    missed)."""
    found = false = 0
    errors = []
    for frame, (x, y) in zip(frames, results, strict=True):
        idx, ok = match(frame.x, frame.y, x, y)
        found += ok.sum()
        false += len(x) - ok.sum()
        err = np.full(frame.x.size, np.nan)
        err[ok] = np.hypot(x[idx[ok]] - frame.x[ok], y[idx[ok]] - frame.y[ok])
        errors.append(err)
    total = sum(f.x.size for f in frames)
    return found / total, false / len(frames), errors


def predictive_time(frame, repeats: int, centroid: str = "windowed", clock: str = "wall"
                    ) -> tuple[float, float, int]:
    rng = np.random.default_rng(3)
    pick = np.arange(min(20, frame.x.size))
    px, py = frame.x[pick] + rng.uniform(-1, 1, pick.size), frame.y[pick] + rng.uniform(-1, 1, pick.size)
    detector = StarDetector(centroid=centroid)
    result = detector.measure_windows(frame.image, px, py, 6)
    samples, now = [], CLOCKS[clock]
    for _ in range(repeats * 5):
        t0 = now()
        detector.measure_windows(frame.image, px, py, 6)
        samples.append(now() - t0)
    return float(np.median(samples)), float(np.min(samples)), len(result)


def peers(frames: list, repeats: int, clock: str = "wall") -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        src, out = Path(tmp) / "frames.npz", Path(tmp) / "peers.npz"
        np.savez(src, frames=np.stack([f.image for f in frames]), psf_sigma_px=PSF_SIGMA_PX)
        raw = run_peers(src, out, repeats=repeats, clock=clock)
    res = {}
    for name in ("sep", "sep_win", "dao"):
        per_frame = [(raw[f"{name}_x"][raw[f"{name}_frame"] == k],
                      raw[f"{name}_y"][raw[f"{name}_frame"] == k]) for k in range(len(frames))]
        res[name] = (per_frame, raw[f"{name}_time_s"], raw[f"{name}_best_s"])
    res["versions"] = tuple(raw["versions"])
    return res


def report(rows: dict, frames: list) -> None:
    scores = {name: score(frames, res) for name, (res, _, _) in rows.items()}
    common = np.all([np.isfinite(np.concatenate(s[2])) for s in scores.values()], axis=0)
    ref = np.median(rows["startrack (default)"][1])
    sep = np.median(rows["SEP extract"][1]) if "SEP extract" in rows else np.nan
    print(f"\n{'method':<26}{'median ms':>10}{'best ms':>8}{'x ours':>8}{'x SEP':>7}{'complete':>10}"
          f"{'false/fr':>9}{'rms px':>8}{'rms common':>11}")
    for name, (_, times, best) in rows.items():
        comp, false, errors = scores[name]
        err = np.concatenate(errors)
        rms = np.sqrt(np.nanmean(err**2))
        rms_common = np.sqrt(np.mean(err[common] ** 2))
        ms = np.median(times) * 1e3
        print(f"{name:<26}{ms:10.2f}{np.min(best) * 1e3:8.2f}{ms / (ref * 1e3):8.2f}{ms / (sep * 1e3):7.2f}"
              f"{comp:10.3f}{false:9.1f}{rms:8.4f}{rms_common:11.4f}")
    print(f"(rms common: over the {common.sum()} of {common.size} stars every method found)")


def frame_passes(shape: tuple[int, int], itemsize: int, binning: int = 2) -> list[tuple[str, int]]:
    """The default detector's whole-frame passes on an (H, W) frame of ``itemsize``-byte pixels,
    each with the bytes it reads and writes (the detection image and its maps are float32 on
    the binned grid; the statistics' subsamples of the full frame, a few per cent of it, and
    the per-spot work are left out)."""
    frame = shape[0] * shape[1] * itemsize
    binned = (shape[0] // binning) * (shape[1] // binning) * 4
    return [
        ("bin: read the frame, write the binned image", frame + binned),
        ("smooth 3 x 3 (one fused pass): read, write", 2 * binned),
        ("tile samples: read, write the stack", 2 * binned),
        ("sort the stack in place", 2 * binned),
        ("residuals: read, write the stack and the level map", 3 * binned),
        ("sort the residual stack in place", 2 * binned),
        ("significance: read image and level, write", 3 * binned),
        ("threshold: read the significance, write the mask", binned + binned // 4),
        ("label: read the mask", binned // 4),
    ]


def bandwidth_floor(frame: np.ndarray, repeats: int = 50) -> None:
    """Print the copy bandwidth of the frame (bytes read + written by ``np.copyto``, median of
    ``repeats``) and the time the default detector's passes (:func:`frame_passes`) take at it."""
    out = np.empty_like(frame)
    np.copyto(out, frame)
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.copyto(out, frame)
        samples.append(time.perf_counter() - t0)
    rate = 2 * frame.nbytes / float(np.median(samples))
    passes = frame_passes(frame.shape, frame.itemsize)
    total = sum(n for _, n in passes)
    print(f"\nmemory-bandwidth floor: a numpy copy of the {frame.shape[0]} x {frame.shape[1]} "
          f"{frame.dtype} frame moves {rate / 1e9:.1f} GB/s ({np.median(samples) * 1e3:.3f} ms median)")
    for name, n in passes:
        print(f"  {name:<52}{n / frame.nbytes:6.2f} frames")
    print(f"  total {total / frame.nbytes:.2f} frames = {total / 2**20:.1f} MiB: "
          f"{total / rate * 1e3:.3f} ms at that bandwidth (the floor of these passes)")


def huge_frame_memory(size: int = 20_000) -> None:
    """Peak traced memory of detect() on a size x size uint16 frame with 400 stars."""
    rng = np.random.default_rng(5)
    image = np.empty((size, size), dtype=np.uint16)
    for start in range(0, size, 1000):
        band = rng.standard_normal((min(1000, size - start), size), dtype=np.float32)
        image[start: start + band.shape[0]] = np.clip(100 + 5 * band, 0, 65535)
    x, y = rng.uniform(50, size - 50, 400), rng.uniform(50, size - 50, 400)
    stamp = render_gaussian_psf((21, 21), [10.0], [10.0], [2e4], PSF_SIGMA_PX)
    for xi, yi in zip(x.astype(int), y.astype(int), strict=True):
        image[yi - 10: yi + 11, xi - 10: xi + 11] += stamp.astype(np.uint16)
    tracemalloc.start()
    t0 = time.perf_counter()
    det = StarDetector().detect(image)
    elapsed = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    idx, ok = match(x.astype(int) + 0.0, y.astype(int) + 0.0, det.x, det.y)
    strip = StarDetector().max_block_px
    print(f"\n{size} x {size} uint16 frame ({image.nbytes / 2**20:.0f} MiB input): {len(det)} "
          f"detections, {ok.sum()} of 400 stars, {elapsed:.1f} s; peak traced memory "
          f"{peak / 2**20:.0f} MiB = {peak / strip:.1f} bytes per pixel of a {strip / 1e6:.1f} Mpx "
          f"strip (the input itself not counted)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-peers", action="store_true")
    parser.add_argument("--huge", action="store_true", help="also the 20,000 x 20,000 frame")
    add_clock_option(parser)
    args = parser.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.2f}; times by the "
          f"{clock_name(args.clock)}")
    frames = make_frames(args.frames, args.seed)
    detectors = {"startrack (default)": StarDetector(), "startrack, no fine pass": _without_fine_pass(),
                 "startrack weighted": StarDetector(centroid="weighted"), "startrack mle": StarDetector(centroid="mle")}
    rows = {name: time_ours(detector, frames, args.repeats, args.clock) for name, detector in detectors.items()}
    if not args.no_peers:
        peer = peers(frames, args.repeats, args.clock)
        print(f"SEP {peer['versions'][0]}, photutils {peer['versions'][1]}")
        rows["SEP extract"] = peer["sep"]
        rows["SEP extract + winpos"] = peer["sep_win"]
        rows["photutils DAOStarFinder"] = peer["dao"]
    report(rows, frames)
    bandwidth_floor(frames[0].image)
    print()
    for centroid in ("windowed", "weighted"):
        t, best, n = predictive_time(frames[0], args.repeats, centroid, args.clock)
        print(f"predictive pass, 20 windows of 13 x 13 px, {centroid} centroid: {t * 1e3:.3f} ms median, "
              f"{best * 1e3:.3f} ms best, {n} found (issue 5 target: < 1 ms)")
    print(f"load average {os.getloadavg()[0]:.2f}")
    if args.huge:
        huge_frame_memory()
    return 0


if __name__ == "__main__":
    sys.exit(main())
