"""Real photos with what night-sky photos carry besides stars, solved with no hint.

The eight photos of ``../shared/realdata`` are altered by ``hazard_renders.py``. The hazards are
15 captions and a logo burnt in, the Moon's glow at three places, the Moon's disc in the frame,
hot pixels (in pairs and triples at 0.1 %, alone and in clusters at 1 %), satellite and aircraft
trails, and partial clouds. Each variant is saved in its photo's own format (JPEG quality 90, or
PNG) and solved from the file with ``solve_image`` and no hint. Hot pixels are the exception:
they are set in the pixels after the photo is read, as a sensor makes them.

Per hazard it prints:

- how many variants solved right: the image centre within 2 px of astrometry.net's
  (``truth.csv``);
- the median solve time;
- the share of astrometry.net's matched stars detected within 2 px, for the glow and the Moon;
- for the clouds, the share of matched stars in clear sky (cover under 5 %) detected, beside the
  same stars on the photo without clouds.

    .venv/bin/python benchmarks/photo_hazards.py [--hazards captions glow ...] [--seed 1]
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))

import hazard_renders as hz  # noqa: E402
from detect_realdata import IMAGES, REALDATA, reference  # noqa: E402
from realdata_benchmark import centre_error_px  # noqa: E402

from startrack import solve_image  # noqa: E402

MATCH_PX = 2.0
CLEAR_SKY = 0.05


def variants(name: str, hazard: str, rng: np.random.Generator) -> Iterator[tuple[np.ndarray, np.ndarray | None]]:
    """The altered RGB images (float grey levels) of photo ``name`` for ``hazard``, each with the
    cloud cover where there is one."""
    rgb = np.asarray(Image.open(REALDATA / IMAGES[name] / name).convert("RGB"), dtype=np.float64)
    if hazard == "captions":
        yield from ((hz.caption(rgb, spec), None) for spec in hz.CAPTIONS)
        yield hz.logo(rgb), None
    elif hazard == "glow":
        yield from ((hz.glow(rgb, spec), None) for spec in hz.GLOWS)
    elif hazard == "moon":
        yield from ((hz.moon(rgb, spec), None) for spec in hz.MOONS)
    elif hazard == "trails":
        yield from ((hz.trails(rgb, spec, rng), None) for spec in hz.TRAILS)
    elif hazard == "clouds":
        yield from (hz.clouds(rgb, spec, rng) for spec in hz.CLOUDS)
    else:  # hot pixels: "hot 0.1 %" or "hot 1 %", set in the pixels as read
        share = 0.001 if hazard == "hot 0.1 %" else 0.01
        shapes = ("pair", "triple") if share < 0.005 else ("single", "pair", "triple")
        yield from ((hz.hot_pixels(rgb, shape, share, rng), None) for shape in shapes)


def solve_variant(image: np.ndarray, name: str, hazard: str, folder: Path):
    """Solve one variant with no hint: from a file in the photo's format, or as pixels (hot
    pixels); returns the solution and the seconds it took."""
    pixels = np.clip(image, 0, 255).astype(np.uint8)
    if hazard.startswith("hot"):
        source: object = pixels.sum(axis=2, dtype=np.uint16)
    else:
        source = folder / f"variant{Path(name).suffix}"
        Image.fromarray(pixels).save(source, quality=90)
    t0 = time.perf_counter()
    solution = solve_image(source)
    return solution, time.perf_counter() - t0


def solved_right(solution, row: dict[str, str]) -> bool:
    """Whether the image centre lies within :data:`MATCH_PX` of astrometry.net's."""
    return bool(solution.solved and centre_error_px(solution, row) < MATCH_PX)


def found_stars(solution, ref) -> np.ndarray:
    """Shape (M,): which of astrometry.net's matched stars have a detection within 2 px."""
    det = solution.detections
    if det is None or len(det) == 0:
        return np.zeros(ref.x.size, dtype=bool)
    return np.hypot(ref.x[:, None] - det.x[None], ref.y[:, None] - det.y[None]).min(axis=1) < MATCH_PX


def run_hazard(hazard: str, rows: dict[str, dict[str, str]], seed: int, baseline: dict) -> dict:
    """Solve every variant of ``hazard`` on every photo; counts for :func:`print_row`."""
    rng = np.random.default_rng(seed)
    out = {"n": 0, "right": 0, "times": [], "found": 0, "stars": 0, "clear_found": 0, "clear_base": 0, "clear": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for name in IMAGES:
            ref = reference(name)
            for image, cover in variants(name, hazard, rng):
                solution, seconds = solve_variant(image, name, hazard, Path(tmp))
                found = found_stars(solution, ref)
                out["n"] += 1
                out["right"] += solved_right(solution, rows[name])
                out["times"].append(seconds)
                out["found"] += int(found.sum())
                out["stars"] += found.size
                if cover is not None:
                    clear = cover[np.clip(np.rint(ref.y).astype(int), 0, cover.shape[0] - 1),
                                  np.clip(np.rint(ref.x).astype(int), 0, cover.shape[1] - 1)] < CLEAR_SKY
                    out["clear"] += int(clear.sum())
                    out["clear_found"] += int((found & clear).sum())
                    out["clear_base"] += int((baseline[name] & clear).sum())
    return out


def print_row(hazard: str, r: dict) -> None:
    recall = f"{r['found']} / {r['stars']}" if hazard in ("glow", "moon") else ""
    if r["clear"]:
        recall = f"clear sky {r['clear_found']} / {r['clear']} (without clouds {r['clear_base']})"
    print(f"{hazard:<10}{r['n']:>9}{r['right']:>8}{np.median(r['times']) * 1e3:>11.1f}  {recall}", flush=True)


def main(argv: list[str] | None = None) -> int:
    hazards = ("captions", "glow", "moon", "hot 0.1 %", "hot 1 %", "trails", "clouds")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hazards", nargs="+", choices=hazards, default=list(hazards))
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    with open(REALDATA / "truth.csv", newline="") as fh:
        rows = {row["file"]: row for row in csv.DictReader(fh)}
    solve_image(REALDATA / IMAGES["roof.jpg"] / "roof.jpg")  # loads the databases before any timed solve
    baseline = {name: found_stars(solve_image(REALDATA / folder / name), reference(name))
                for name, folder in IMAGES.items()}  # the matched stars detected without a hazard
    print(f"{'hazard':<10}{'variants':>9}{'right':>8}{'median ms':>11}  matched stars detected")
    for hazard in args.hazards:
        print_row(hazard, run_hazard(hazard, rows, args.seed, baseline))
    return 0


if __name__ == "__main__":
    sys.exit(main())
