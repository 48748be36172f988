"""One-shot-colour (Bayer mosaic) FITS frames, and an X-Trans mosaic: detected and solved as read,
against the same frame from a grey sensor.

A one-shot-colour astronomy camera saves raw photosites under an RGGB filter mosaic
(:mod:`startrack.io._mosaic`). Each frame here is the Hipparcos sky (V <= 8.5) through a 2000 x
1500 px camera of 15 deg (``startrack.simulate.simulate_frame``, noise off, the generic CMOS
sensor's optics and PSF), at a random attitude. Its light in electrons is then taken through
per-site responses (R 0.45, G 1.0, B 0.6 of a grey pixel's, the same for every star: a white
star's raw colour) over a light-polluted sky of its own colour (R 250, G 350, B 120 e- per pixel),
with Poisson and 5 e- read noise and a bias of 100 ADU at 1 e-/ADU. The grey sensor's frame has
the same stars at a response of 1 and a sky of 350 e-. Three cases: a PSF of 1.0 and of 1.6 px sd,
and 1.0 px with 0.05 % of the pixels hot (the same pixels in both frames, 300-5000 counts added:
an uncooled sensor in a long exposure, no dark frame subtracted). The same light also falls on a
sensor under Fujifilm's 6 x 6 X-Trans filters (the same responses and sky colours; the same hot
pixels).

Read eight ways, each solved with ``solve_image`` and no hint:

* ``grey sensor``: the grey frame (the reference);
* ``mosaic as grey pixels``: the mosaic's array as it is (how a FITS file was read before
  :mod:`._mosaic`);
* ``FITS, BAYERPAT``: the mosaic in a FITS file naming its pattern (full-resolution luminance);
* ``FITS, no BAYERPAT``: the same without the card (the pattern found in the pixels);
* ``FITS, BAYERPAT, green``: ``channel="g"``, the green sites interpolated;
* ``2 x 2 cell sums``: the cells summed as :func:`startrack.io._raw.read_raw` sums a camera RAW
  file's (:func:`startrack.io.bayer_cells`, half resolution; positions mapped back with
  :func:`startrack.io.full_resolution_xy`), which is how ``read_image`` read RAW files before it
  read them as the FITS mosaics above;
* ``X-Trans as grey pixels``: the X-Trans frame's array as it is;
* ``X-Trans, site by site``: that frame less its bias through :func:`startrack.io.mosaic_to_plane`
  (:mod:`startrack.io._cfa`, as ``read_image`` reads such a camera RAW file).

Printed per way and case: rendered stars matched to a detection within 1.5 px (mean per frame; each
detection matched once, ``detect_frames.match``) and the detections left unmatched, the RMS
centroid error over the stars every way found, the frames solved, and the median boresight error
against the truth.

    .venv/bin/python benchmarks/bayer_fits.py [--frames 10] [--seed 1]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np
from astropy.io import fits

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_frames import match  # noqa: E402

from startrack import solve_image  # noqa: E402
from startrack.camera import Camera  # noqa: E402
from startrack.frames import angle_between, boresight  # noqa: E402
from startrack.io import bayer_cells, full_resolution_xy, mosaic_to_plane  # noqa: E402
from startrack.simulate import get_sensor_preset, random_attitude, simulate_frame  # noqa: E402
from startrack.units import ARCSEC  # noqa: E402

CAMERA = Camera.from_fov(2000, 1500, 15.0)
SHAPE = (CAMERA.height, CAMERA.width)
PATTERN = "RGGB"
XTRANS = "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"
RESPONSE = {"R": 0.45, "G": 1.0, "B": 0.6}
SKY_E = {"R": 250.0, "G": 350.0, "B": 120.0}
GREY_SKY_E, BIAS_ADU, READ_NOISE_E, MAX_MAG = 350.0, 100.0, 5.0, 8.5
MATCH_PX = 1.5
CASES = ((1.0, 0.0), (1.6, 0.0), (1.0, 0.0005))
"""(PSF sigma px, fraction of the pixels hot) of each table."""
WAYS = ("grey sensor", "mosaic as grey pixels", "FITS, BAYERPAT", "FITS, no BAYERPAT", "FITS, BAYERPAT, green",
        "2 x 2 cell sums", "X-Trans as grey pixels", "X-Trans, site by site")


def site_map(values: dict[str, float], shape: tuple[int, int], pattern: str = PATTERN) -> np.ndarray:
    """The value of each pixel's filter colour, for the mosaic of ``shape`` whose first cell is
    ``pattern`` (four letters, or rows joined by "/")."""
    rows = pattern.split("/") if "/" in pattern else [pattern[:2], pattern[2:]]
    cell = np.array([[values[c] for c in row] for row in rows], dtype=float)
    reps = (shape[0] // cell.shape[0] + 1, shape[1] // cell.shape[1] + 1)
    return np.tile(cell, reps)[:shape[0], :shape[1]]


def exposed(light_e: np.ndarray, response: np.ndarray | float, sky_e: np.ndarray | float,
            rng: np.random.Generator) -> np.ndarray:
    """Counts (uint16 ADU) of a frame whose stars give ``light_e`` electrons through a grey pixel."""
    electrons = rng.poisson(np.maximum(light_e * response + sky_e, 0.0)) + rng.normal(0.0, READ_NOISE_E, light_e.shape)
    return np.clip(np.rint(electrons + BIAS_ADU), 0, 65535).astype(np.uint16)


def with_hot_pixels(frames: tuple[np.ndarray, ...], fraction: float, rng: np.random.Generator) -> list[np.ndarray]:
    """The frames (uint16, one shape) with the same ``fraction`` of their pixels hot: 300-5000 counts
    added, uniformly."""
    n = int(round(fraction * frames[0].size))
    iy, ix = rng.integers(0, frames[0].shape[0], n), rng.integers(0, frames[0].shape[1], n)
    extra = rng.uniform(300.0, 5000.0, n)
    out = []
    for frame in frames:
        hot = frame.astype(np.float64)
        hot[iy, ix] += extra
        out.append(np.clip(hot, 0, 65535).astype(np.uint16))
    return out


def fits_file(folder: Path, name: str, data: np.ndarray, pattern: str | None) -> Path:
    """``data`` written to ``folder/name.fits``, with ``BAYERPAT`` = ``pattern`` when one is given."""
    header = fits.Header()
    if pattern:
        header["BAYERPAT"] = pattern
    path = folder / f"{name}.fits"
    fits.PrimaryHDU(data, header).writeto(path, overwrite=True)
    return path


def solve_ways(grey: np.ndarray, mosaic: np.ndarray, xtrans: np.ndarray, folder: Path) -> dict[str, tuple]:
    """Each way's (solution, detected x, detected y) in full-resolution pixels."""
    with_card, without = fits_file(folder, "card", mosaic, PATTERN), fits_file(folder, "plain", mosaic, None)
    out = {}
    for way, source, kwargs in (("grey sensor", grey, {}), ("mosaic as grey pixels", mosaic, {}),
                                ("FITS, BAYERPAT", with_card, {}), ("FITS, no BAYERPAT", without, {}),
                                ("FITS, BAYERPAT, green", with_card, {"channel": "g"}),
                                ("2 x 2 cell sums", bayer_cells(mosaic.astype(np.int64) - int(BIAS_ADU),
                                                                np.array([[0, 1], [3, 2]])), {}),
                                ("X-Trans as grey pixels", xtrans, {}),
                                ("X-Trans, site by site", mosaic_to_plane(xtrans.astype(np.float32) - BIAS_ADU, XTRANS),
                                 {})):
        solution = solve_image(source, **kwargs)
        x, y = solution.detections.x, solution.detections.y
        if way == "2 x 2 cell sums":
            x, y = full_resolution_xy(x, y)
        out[way] = (solution, np.asarray(x), np.asarray(y))
    return out


def frame_rows(psf_sigma_px: float, frames: int, seed: int, hot: float = 0.0) -> dict[str, dict[str, list]]:
    """Per way, per frame: rendered stars found, other detections, the squared centroid errors (px^2)
    of the stars every way found, and the boresight error (arcsec, NaN when not solved)."""
    sensor = get_sensor_preset("generic-cmos")
    sensor = dataclasses.replace(sensor, optics=dataclasses.replace(sensor.optics, psf_sigma_px=psf_sigma_px))
    rng = np.random.default_rng([seed, int(psf_sigma_px * 10), int(hot * 1e5)])
    rows: dict[str, dict[str, list]] = {way: {"found": [], "other": [], "err2": [], "bore": []} for way in WAYS}
    response, sky = site_map(RESPONSE, SHAPE), site_map(SKY_E, SHAPE)
    x_response, x_sky = site_map(RESPONSE, SHAPE, XTRANS), site_map(SKY_E, SHAPE, XTRANS)
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(frames):
            truth = random_attitude(rng)
            sim = simulate_frame(CAMERA, truth, max_mag=MAX_MAG, sensor=sensor, epoch_jyear=2000.0, noise=False)
            light = sim.image.astype(float) - sensor.detector.bias_adu
            frames = (exposed(light, 1.0, GREY_SKY_E, rng), exposed(light, response, sky, rng),
                      exposed(light, x_response, x_sky, rng))
            grey, mosaic, xtrans = with_hot_pixels(frames, hot, rng)
            tx, ty = np.asarray(sim.truth.x), np.asarray(sim.truth.y)
            add_frame(rows, solve_ways(grey, mosaic, xtrans, Path(tmp)), tx, ty, truth)
    return rows


def add_frame(rows: dict[str, dict[str, list]], solved: dict[str, tuple], tx: np.ndarray, ty: np.ndarray,
              truth) -> None:
    """One frame's figures per way into ``rows``: each rendered star (tx, ty) matched to one
    detection within :data:`MATCH_PX` (:func:`detect_frames.match`, each detection used once)."""
    matched = {way: match(tx, ty, x, y, MATCH_PX) for way, (_, x, y) in solved.items()}
    everywhere = np.all([found for _, found in matched.values()], axis=0)
    for way, (solution, x, y) in solved.items():
        index, found = matched[way]
        row = rows[way]
        row["found"].append(int(found.sum()))
        row["other"].append(int(x.size - found.sum()))
        j = index[everywhere]
        row["err2"].extend((x[j] - tx[everywhere]) ** 2 + (y[j] - ty[everywhere]) ** 2)
        row["bore"].append(boresight_error_arcsec(solution, truth))


def boresight_error_arcsec(solution, truth) -> float:
    """Angle (arcsec) between the solved and the true boresight (NaN when not solved)."""
    if not solution.solved:
        return float("nan")
    return float(angle_between(boresight(solution.rot_cam_from_icrs), boresight(truth)) / ARCSEC)


def print_rows(psf_sigma_px: float, hot: float, rows: dict[str, dict[str, list]]) -> None:
    """The table of one PSF size and hot-pixel fraction."""
    print(f"\nPSF sigma {psf_sigma_px} px, {hot:.2%} of the pixels hot, {len(rows[WAYS[0]]['found'])} frames")
    print(f"{'read as':24s} {'stars/frame':>11s} {'others':>7s} {'rms px':>7s} {'solved':>7s} {'boresight':>10s}")
    for way in WAYS:
        row = rows[way]
        bore = np.asarray(row["bore"])
        solved = np.isfinite(bore)
        median = f"{np.median(bore[solved]):8.2f} \"" if solved.any() else "       -"
        rms = np.sqrt(np.mean(row["err2"])) if row["err2"] else float("nan")
        print(f"{way:24s} {np.mean(row['found']):11.1f} {np.mean(row['other']):7.1f} {rms:7.3f} "
              f"{solved.sum():3d}/{bore.size:<3d} {median}")
    print(f"(rms px: over the {len(rows[WAYS[0]]['err2'])} rendered stars every way found)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=10, help="frames per PSF size (default 10)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    print(f"{CAMERA.width} x {CAMERA.height} px, {CAMERA.fov_deg:.0f} deg, V <= {MAX_MAG}, {PATTERN} mosaic; "
          f"responses {RESPONSE}, sky {SKY_E} e-, grey sky {GREY_SKY_E:.0f} e-")
    for psf, hot in CASES:
        print_rows(psf, hot, frame_rows(psf, args.frames, args.seed, hot))
    return 0


if __name__ == "__main__":
    sys.exit(main())
