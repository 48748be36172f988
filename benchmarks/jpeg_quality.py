"""Solving JPEGs (or lossy WebP, AVIF) of every quality: the detector's compression noise floor on and off.

A JPEG's quantization turns sky noise into smooth 8 x 8-block patterns the size of a star and
flattens its quietest blocks (:mod:`startrack.detect._compression`). ``solve_image`` on a JPEG
file raises the detector's noise floor to its quantization step (``StarDetector.for_image``);
the same pixels given as an array are detected as they are, which is the "off" column.

Part 1: the eight real images of ``../shared/realdata``, each saved again by Pillow at every
``--qualities`` (grey when its colour planes are equal, else RGB), solved without a hint; a
solve is right when its boresight lies within 0.1 deg of ``truth.csv``'s (astrometry.net's).
Part 2: ``--frames`` simulated star-camera frames (1024 x 1024 px, 15 deg, the FAR-MST sensor
of ``image_path_benchmark.py``, stars to V 7), scaled to 8 bits with the sky's noise at
``--noise-dn`` grey levels, saved at the same qualities and solved with the FOV given; right
within 5 pixel angles of the truth. Printed per quality: how many were solved right with the
floor and without it, the median count of detections and the median solve time (the search
stops at its 5 s limit).

With ``--format webp`` or ``avif`` the files are lossy WebP or AVIF of the same qualities
(Pillow's encoders, libwebp and libavif); those give detection no quantization step, so both
columns are the detector as it is, from the file and from its array.

    .venv/bin/python benchmarks/jpeg_quality.py [--qualities 40 50 60 75 90 95] [--frames 10]
        [--noise-dn 2] [--no-real] [--no-sim] [--format jpeg|webp|avif]
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image as PILImage

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_realdata import REALDATA  # noqa: E402
from image_path_benchmark import EPOCH_JYEAR, benchmark_sensor  # noqa: E402

from startrack import solve_image  # noqa: E402
from startrack.analysis._scoring import attitude_errors_rad, roll_weight, tolerance_rad  # noqa: E402
from startrack.camera import Camera  # noqa: E402
from startrack.frames import angle_between, boresight, radec_to_vector, random_rotations  # noqa: E402
from startrack.io import read_image  # noqa: E402

RIGHT_DEG = 0.1
"""A real image's solve is right when its boresight is this close to astrometry.net's (deg)."""


FORMATS = {"jpeg": ".jpg", "webp": ".webp", "avif": ".avif"}
"""The lossy formats compared, by their file suffix (Pillow picks the encoder from it)."""


def save_lossy(pixels: PILImage.Image, path: Path, quality: int) -> Path:
    """``pixels`` saved at ``quality`` in the format of ``path``'s suffix (:data:`FORMATS`;
    Pillow's default 4:2:0 chroma for a colour JPEG)."""
    pixels.save(path, quality=quality)
    return path


def as_pil(path: Path) -> PILImage.Image:
    """A real image as Pillow opens it, grey when its colour planes are equal, else RGB."""
    image = PILImage.open(path)
    rgb = np.asarray(image.convert("RGB"))
    same = np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 1], rgb[..., 2])
    return image.convert("L") if same else image.convert("RGB")


def solve_both(path: Path, right, **solve_options) -> list[tuple[bool, int, float]]:
    """(right, detections, solve time in s) with the file's floor (the path) and without (its
    array)."""
    out = []
    for source in (path, read_image(path).data):
        solution = solve_image(source, **solve_options)
        n = 0 if solution.detections is None else len(solution.detections)
        out.append((bool(solution.solved and right(solution)), n, solution.solve_time_s))
    return out


def real_cases(folder: Path, qualities: list[int], suffix: str = ".jpg") -> dict[int, list]:
    """Part 1's solves by quality."""
    with open(REALDATA / "truth.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    results: dict[int, list] = {q: [] for q in qualities}
    for row in rows:
        truth = radec_to_vector(np.radians(float(row["ra_center_deg"])), np.radians(float(row["dec_center_deg"])))

        def right(solution, truth=truth) -> bool:
            return float(np.degrees(angle_between(boresight(solution.rot_cam_from_icrs), truth))) < RIGHT_DEG

        pixels = as_pil(REALDATA / row["set"] / row["file"])
        for q in qualities:
            path = save_lossy(pixels, folder / f"{Path(row['file']).stem}_q{q}{suffix}", q)
            results[q].append(solve_both(path, right))
        print(f"  {row['file']} done", file=sys.stderr, flush=True)
    return results


def sim_cases(folder: Path, qualities: list[int], frames: int, noise_dn: float, seed: int,
              suffix: str = ".jpg") -> dict[int, list]:
    """Part 2's solves by quality."""
    from startrack.simulate import simulate_frame

    camera = Camera.from_fov(1024, 1024, 15.0)
    rng = np.random.default_rng(seed)
    sensor = benchmark_sensor(1.0, 1.5)
    tolerance, weight = tolerance_rad(camera), roll_weight(camera)
    results: dict[int, list] = {q: [] for q in qualities}
    for i, rot in enumerate(random_rotations(frames, rng=rng)):
        sim = simulate_frame(camera, rot, rng=rng, sensor=sensor, max_mag=7.0, epoch_jyear=EPOCH_JYEAR)
        level = np.median(sim.image)
        noise = 1.4826 * np.median(np.abs(sim.image - level))
        grey = np.clip(np.rint((sim.image - level) * noise_dn / noise + 4 * noise_dn), 0, 255).astype(np.uint8)

        def right(solution, rot=rot) -> bool:
            return bool(attitude_errors_rad([rot], [solution.rot_cam_from_icrs], weight)[0] <= tolerance)

        for q in qualities:
            path = save_lossy(PILImage.fromarray(grey), folder / f"sim{i:03d}_q{q}{suffix}", q)
            results[q].append(solve_both(path, right, fov_deg=15.0, epoch=EPOCH_JYEAR))
    return results


def print_table(title: str, results: dict[int, list]) -> None:
    print(f"\n{title}")
    print(f"{'quality':>7}  {'right, floor':>12}  {'right, none':>11}  {'detections':>15}  {'median time (ms)':>16}")
    for q, rows in results.items():
        on, off = [r[0] for r in rows], [r[1] for r in rows]
        n = len(rows)
        counts = f"{np.median([r[1] for r in on]):.0f} / {np.median([r[1] for r in off]):.0f}"
        times = f"{np.median([r[2] for r in on]) * 1e3:.0f} / {np.median([r[2] for r in off]) * 1e3:.0f}"
        print(f"{q:>7}  {sum(r[0] for r in on):>8} / {n:<2}  {sum(r[0] for r in off):>7} / {n:<2}  "
              f"{counts:>15}  {times:>16}")
    print("(detections and times: with the floor / without)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--qualities", type=int, nargs="+", default=[40, 50, 60, 75, 90, 95])
    parser.add_argument("--frames", type=int, default=10, help="simulated frames")
    parser.add_argument("--noise-dn", type=float, default=2.0, help="sky noise of the 8-bit frames (grey levels)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-real", action="store_true")
    parser.add_argument("--no-sim", action="store_true")
    parser.add_argument("--format", choices=sorted(FORMATS), default="jpeg")
    args = parser.parse_args(argv)
    suffix = FORMATS[args.format]
    with tempfile.TemporaryDirectory(prefix="startrack-jpeg-") as tmp:
        if not args.no_real and (REALDATA / "truth.csv").is_file():
            print_table(f"real images (../shared/realdata) as {args.format}, no hint",
                        real_cases(Path(tmp), args.qualities, suffix))
        if not args.no_sim:
            print_table(f"simulated 8-bit frames as {args.format}, sky noise {args.noise_dn:g} DN, FOV given",
                        sim_cases(Path(tmp), args.qualities, args.frames, args.noise_dn, args.seed, suffix))
    return 0


if __name__ == "__main__":
    sys.exit(main())
