"""Detections on the eight real images of ``../shared/realdata`` against astrometry.net.

For each image: the stars astrometry.net matched to Tycho-2 (``truth/<image>.corr``, FITS
1-based ``field_x``, ``field_y`` converted to our 0-based convention), how many of them we detect
(within 2 px) among all our detections and among our brightest 30, and our centroid offset from
theirs (median and RMS over the found stars), for three centroiders. The openstartracker frames
are also run with the seed 000 §4.1 median dark built from the three frames themselves (their
own ``median_image.png`` is truncated: only rows 0-48 decode).

    .venv/bin/python benchmarks/detect_realdata.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from astropy.io import fits
from PIL import Image

from startrack.conventions import from_fits_pixels
from startrack.detect import StarDetector, median_frame, to_single_channel

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
IMAGES = {
    "img3.png": "UBNanosatLab-openstartracker", "img4.png": "UBNanosatLab-openstartracker",
    "img6.png": "UBNanosatLab-openstartracker", "crappy.jpg": "smroid-cedar-solve",
    "orion_trees.jpg": "smroid-cedar-solve", "roof.jpg": "smroid-cedar-solve",
    "tree.jpg": "smroid-cedar-solve", "pleiades.jpg": "smroid-cedar-solve",
}
METHODS = ("windowed", "weighted", "mle")


def load(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    folder = REALDATA / IMAGES[name]
    with Image.open(folder / name) as img:
        image = to_single_channel(np.asarray(img))
    corr = fits.getdata(folder / "truth" / (Path(name).stem + ".corr"))
    x, y = from_fits_pixels(np.asarray(corr["field_x"], float), np.asarray(corr["field_y"], float))
    return image, x, y


def row(label: str, det, x: np.ndarray, y: np.ndarray) -> str:
    dist = np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None]) if len(det) else \
        np.full((x.size, 1), np.inf)
    found = dist.min(axis=1) < 2.0
    top = dist[:, :30].min(axis=1) < 2.0
    off = dist.min(axis=1)[found]
    med = np.median(off) if off.size else np.nan
    rms = np.sqrt(np.mean(off**2)) if off.size else np.nan
    return (f"{label:<34}{x.size:>5}{found.sum():>7}{top.sum():>7}{len(det):>7}"
            f"{med:>9.3f}{rms:>8.3f}")


def main(argv: list[str] | None = None) -> int:
    if not (REALDATA / "truth.csv").is_file():
        print(f"real-image folder {REALDATA} is absent")
        return 0
    print(f"{'image / centroider':<34}{'corr':>5}{'found':>7}{'top30':>7}{'dets':>7}"
          f"{'med px':>9}{'rms px':>8}")
    loaded = {name: load(name) for name in IMAGES}
    dark = median_frame([loaded[n][0] for n in ("img3.png", "img4.png", "img6.png")])
    for name, (image, x, y) in loaded.items():
        for method in METHODS:
            det = StarDetector(centroid=method).detect(image)
            print(row(f"{name} {method}", det, x, y))
        if IMAGES[name].startswith("UBNanosat"):
            det = StarDetector(dark_frame=dark).detect(image)
            print(row(f"{name} windowed + median dark", det, x, y))
    print("found: within 2 px among all detections; top30: among our brightest 30; med / rms "
          "px: our offset from astrometry.net's position over the found stars")
    return 0


if __name__ == "__main__":
    sys.exit(main())
