"""Real photos after what a photographer's workflow does to them, solved with no hint.

The eight real images of ``../shared/realdata`` are turned (90, 180, 270 deg), cropped (the
central 60 % of each side; the top-left 71 %, half the area), resized (x 0.5 and x 2, and to
thumbnails 256 and 200 px wide; Lanczos),
stretched (gamma 0.5, asinh, 1-99 % levels), re-saved as a quality-60 JPEG, reduced to grey or
to the green plane, given a colour cast, smoothed (Gaussian sd 1 px, 3 x 3 median), sharpened
(unsharp mask), saved as 16-bit grey PNG and TIFF, padded (a black canvas 1.5 times the size, a
white 20 px frame), vignetted (corners 60 % darker) and given a sky gradient (0 to 120 grey
levels down the frame), and trailed (stars drawn out 12 and 24 px, as from a fixed tripod:
:func:`trailed`). Each variant is saved in its photo's format (JPEG quality 95, or PNG)
unless its transformation names another, and solved from the file by ``solve_image`` with no hint.

A solve is right when the direction it gives the variant's centre lies within :data:`RIGHT_PX`
pixels (of the variant's own scale) of astrometry.net's direction (``truth/<image>.wcs``) of the
original pixel that centre came from. Printed per transformation: right, wrong (solved farther
off), not solved, and the median solve time; then each variant not solved right, with its reason.

    .venv/bin/python benchmarks/photo_transforms.py [--only roof.jpg ...]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from astropy.wcs import WCS
from PIL import Image
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_realdata import IMAGES, REALDATA, truth_wcs  # noqa: E402

from startrack import solve_image  # noqa: E402
from startrack.frames import angle_between, radec_to_vector  # noqa: E402
from startrack.units import ARCSEC, DEG  # noqa: E402

RIGHT_PX = 2.0
"""A solve is right within this many of the variant's pixels at its centre."""


class Variant(NamedTuple):
    """A transformed photo: its pixels (H, W) or (H, W, 3), float grey levels (0-255, or 0-65535
    for ``save_as`` "png16" and "tif16"), how it is saved ("photo": as the original; "jpg60",
    "png16", "tif16"), the original pixel (x, y) each of its pixels came from, and its pixel
    scale over the original's."""

    pixels: np.ndarray
    save_as: str
    to_original: Callable[[float, float], tuple[float, float]]
    scale: float = 1.0


def _same(x: float, y: float) -> tuple[float, float]:
    return x, y


def geometric(rgb: np.ndarray) -> dict[str, Variant]:
    """Turned, cropped, resized and padded variants (the pixel mappings of ``np.rot90``, slicing,
    Pillow's centre-aligned resize and the canvas offsets)."""
    h, w = rgb.shape[:2]
    out = {"turned 90": Variant(np.rot90(rgb, 1), "photo", lambda x, y: (w - 1 - y, x)),
           "turned 180": Variant(np.rot90(rgb, 2), "photo", lambda x, y: (w - 1 - x, h - 1 - y)),
           "turned 270": Variant(np.rot90(rgb, 3), "photo", lambda x, y: (y, h - 1 - x))}
    cw, ch = round(0.6 * w), round(0.6 * h)
    x0, y0 = (w - cw) // 2, (h - ch) // 2
    out["crop centre 60 %"] = Variant(rgb[y0:y0 + ch, x0:x0 + cw], "photo", lambda x, y: (x + x0, y + y0))
    out["crop top-left 71 %"] = Variant(rgb[: round(0.71 * h), : round(0.71 * w)], "photo", _same)
    for label, factor in (("resized x 0.5", 0.5), ("resized x 2", 2.0), ("256 px wide", 256 / w),
                          ("200 px wide", 200 / w)):
        size = (round(w * factor), round(h * factor))
        pixels = np.asarray(Image.fromarray(_clip8(rgb)).resize(size, Image.LANCZOS), dtype=np.float64)
        out[label] = Variant(pixels, "photo", lambda x, y, s=size: ((x + 0.5) * w / s[0] - 0.5,
                                                                    (y + 0.5) * h / s[1] - 0.5), w / size[0])
    pad = np.zeros((round(1.5 * h), round(1.5 * w), 3))
    py, px = (pad.shape[0] - h) // 2, (pad.shape[1] - w) // 2
    pad[py:py + h, px:px + w] = rgb
    out["black canvas 1.5 x"] = Variant(pad, "photo", lambda x, y: (x - px, y - py))
    frame = np.pad(rgb, ((20, 20), (20, 20), (0, 0)), constant_values=255.0)
    out["white frame 20 px"] = Variant(frame, "photo", lambda x, y: (x - 20, y - 20))
    return out


def tonal(rgb: np.ndarray) -> dict[str, Variant]:
    """Stretched, re-compressed, grey, single-plane, colour-cast, smoothed, sharpened, 16-bit,
    vignetted and graded variants (the pixel grid unchanged)."""
    unit = rgb / 255.0
    lo, hi = np.percentile(rgb, [1, 99])
    h, w = rgb.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    r2 = ((xx - (w - 1) / 2) ** 2 + (yy - (h - 1) / 2) ** 2) / (((w - 1) / 2) ** 2 + ((h - 1) / 2) ** 2)
    grey16 = _grey8(rgb).astype(np.float64) * 257.0
    pixels = {
        "gamma 0.5": (255.0 * unit**0.5, "photo"),
        "asinh stretch": (255.0 * np.arcsinh(20.0 * unit) / np.arcsinh(20.0), "photo"),
        "levels 1-99 %": ((rgb - lo) / max(hi - lo, 1.0) * 255.0, "photo"),
        "JPEG quality 60": (rgb, "jpg60"),
        "grey": (_grey8(rgb).astype(np.float64), "photo"),
        "green plane": (rgb[..., 1], "photo"),
        "colour cast": (rgb * np.array([1.6, 1.0, 0.6]), "photo"),
        "Gaussian sd 1 px": (ndimage.gaussian_filter(rgb, (1, 1, 0)), "photo"),
        "median 3 x 3": (ndimage.median_filter(rgb, size=(3, 3, 1)), "photo"),
        "unsharp mask": (2.0 * rgb - ndimage.gaussian_filter(rgb, (2, 2, 0)), "photo"),
        "16-bit PNG": (grey16, "png16"),
        "16-bit TIFF": (grey16, "tif16"),
        "vignette 60 %": (rgb * (1.0 - 0.6 * r2)[..., None], "photo"),
        "gradient 120": (rgb + (120.0 * yy / (h - 1))[..., None], "photo"),
    }
    return {label: Variant(p, how, _same) for label, (p, how) in pixels.items()}


TRAIL_ANGLE_DEG = 20.0
"""Direction of the star trails of :func:`trailed`, from +x towards +y."""


def trailed(rgb: np.ndarray) -> dict[str, Variant]:
    """The photo as an exposure from a fixed tripod: every star drawn out into a straight trail of
    12 or 24 px (the photo convolved with a line), and the noise that the convolution smoothed
    away added back (a pixel's noise estimated from its difference with the 5 x 5 median), so
    that the sky is as noisy as the photo's own. A trail's light centroid is the star's position
    at mid-exposure, the original position."""
    grey = rgb.mean(axis=2)
    sigma = 1.4826 * float(np.median(np.abs(grey - ndimage.median_filter(grey, 5))))
    rng = np.random.default_rng(0)
    out = {}
    for length in (12.0, 24.0):
        kernel = line_kernel(length, TRAIL_ANGLE_DEG)
        lost = sigma * np.sqrt(max(1.0 - float((kernel**2).sum()), 0.0))
        pixels = np.stack([ndimage.convolve(rgb[..., c], kernel, mode="nearest") for c in range(3)], axis=-1)
        out[f"trailed {length:.0f} px"] = Variant(pixels + rng.normal(0.0, lost, grey.shape)[..., None], "photo", _same)
    return out


def line_kernel(length_px: float, angle_deg: float) -> np.ndarray:
    """A normalised kernel (odd square) of a straight segment of ``length_px`` through its centre
    at ``angle_deg``, sampled every 1/8 px and spread bilinearly over the pixels."""
    size = int(np.ceil(length_px)) + 3
    size += 1 - size % 2
    kernel = np.zeros((size, size))
    along = np.linspace(-length_px / 2, length_px / 2, int(length_px * 8) + 1)
    x = size // 2 + along * np.cos(np.radians(angle_deg))
    y = size // 2 + along * np.sin(np.radians(angle_deg))
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    for dx, dy, weight in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy), (1, 1, fx * fy)):
        np.add.at(kernel, (y0 + dy, x0 + dx), weight)
    return kernel / kernel.sum()


def _grey8(rgb: np.ndarray) -> np.ndarray:
    """Pillow's grey ("L") of an RGB array of grey levels."""
    return np.asarray(Image.fromarray(_clip8(rgb)).convert("L"))


def _clip8(pixels: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(pixels), 0, 255).astype(np.uint8)


def save(variant: Variant, stem: Path, photo_suffix: str) -> Path:
    """The variant written as its ``save_as`` says, next to ``stem``."""
    if variant.save_as in ("png16", "tif16"):
        path = stem.with_suffix(".png" if variant.save_as == "png16" else ".tif")
        Image.fromarray(np.clip(np.rint(variant.pixels), 0, 65535).astype(np.uint16)).save(path)
        return path
    suffix = ".jpg" if variant.save_as == "jpg60" else photo_suffix
    path = stem.with_suffix(suffix)
    quality = 60 if variant.save_as == "jpg60" else 95
    Image.fromarray(_clip8(variant.pixels)).save(path, **({"quality": quality} if suffix == ".jpg" else {}))
    return path


def centre_error_px(solution, variant: Variant, shape: tuple[int, ...], truth: WCS, scale_arcsec: float) -> float:
    """Angle between the solved direction of the variant's centre and the truth's direction of
    the original pixel it came from, in the variant's pixels."""
    h, w = shape[:2]
    x, y = variant.to_original((w - 1) / 2, (h - 1) / 2)
    ra, dec = truth.all_pix2world([x], [y], 0)
    expected = radec_to_vector(ra[0] * DEG, dec[0] * DEG)
    solved = solution.rot_cam_from_icrs.inv().apply(solution.camera.pixel_to_vector((w - 1) / 2, (h - 1) / 2))
    return float(angle_between(solved, expected) / (scale_arcsec * variant.scale * ARCSEC))


def run_image(name: str, folder: Path) -> list[dict]:
    """Every variant of one photo, solved: a row per variant."""
    truth = truth_wcs(name)[0]
    scale = float(np.sqrt(abs(np.linalg.det(truth.pixel_scale_matrix)))) * 3600.0
    rgb = np.asarray(Image.open(REALDATA / IMAGES[name] / name).convert("RGB"), dtype=np.float64)
    rows = []
    for label, variant in {**geometric(rgb), **tonal(rgb), **trailed(rgb)}.items():
        path = save(variant, folder / f"{Path(name).stem} {label}", Path(name).suffix)
        t0 = time.perf_counter()
        solution = solve_image(path)
        seconds = time.perf_counter() - t0
        shape = variant.pixels.shape
        error = centre_error_px(solution, variant, shape, truth, scale) if solution.solved else np.nan
        rows.append({"image": name, "variant": label, "status": solution.status.value, "reason": solution.reason,
                     "error_px": error, "seconds": seconds})
    return rows


def print_table(rows: list[dict]) -> None:
    print(f"{'variant':<20}{'right':>7}{'wrong':>7}{'not solved':>12}{'median ms':>11}")
    for label in dict.fromkeys(r["variant"] for r in rows):
        mine = [r for r in rows if r["variant"] == label]
        right = sum(r["error_px"] < RIGHT_PX for r in mine)
        solved = sum(np.isfinite(r["error_px"]) for r in mine)
        print(f"{label:<20}{right:>7}{solved - right:>7}{len(mine) - solved:>12}"
              f"{np.median([r['seconds'] for r in mine]) * 1e3:>11.1f}")
    for r in rows:
        if not r["error_px"] < RIGHT_PX:
            off = f"{r['error_px']:.1f} px off" if np.isfinite(r["error_px"]) else r["reason"]
            print(f"  {r['image']}, {r['variant']}: {r['status']}: {off}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=sorted(IMAGES), default=sorted(IMAGES, key=list(IMAGES).index))
    args = parser.parse_args(argv)
    solve_image(REALDATA / IMAGES["roof.jpg"] / "roof.jpg")  # loads the databases before any timed solve
    with tempfile.TemporaryDirectory(prefix="startrack-transforms-") as tmp:
        rows = [row for name in args.only for row in run_image(name, Path(tmp))]
    print_table(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
