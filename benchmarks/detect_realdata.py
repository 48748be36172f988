"""Detections on the eight real images of ``../shared/realdata`` against astrometry.net, beside SEP.

Reference stars per image (``../shared/realdata/README.md``):

* **matched**: the image stars astrometry.net matched to Tycho-2 (``truth/<image>.corr``, FITS
  1-based ``field_x``, ``field_y`` converted to our 0-based convention), less the rows whose image
  star lies more than :data:`CORR_TOLERANCE_PX` from the catalogue star's own position in the
  image (``index_x``, ``index_y``): those are chance coincidences of its match radius (two in
  ``roof.jpg``, 6 and 10 px off, on a roof edge and a noise bump; one in ``orion_trees.jpg`` and
  ``tree.jpg``). The genuine matches are 12, 12, 16, 12, 26, 33, 24 and 30 stars.
* **Hipparcos**: every Hipparcos star projected into the image by astrometry.net's TAN-SIP
  solution (``truth/<image>.wcs``), to confirm detections that astrometry.net did not match.

Per image and detector: how many matched stars are detected within :data:`MATCH_RADIUS_PX`
(recall), how many of them are among the brightest 30, the number of detections, the
**unconfirmed** detections (within 2 px of neither a matched nor a Hipparcos star: false
detections, or real stars fainter than Hipparcos's completeness, about V 8-9), how many of the
found stars our point-source quality accepts, and the median offset from astrometry.net's
positions. The openstartracker frames are also run with the Huffman 2006 §4.1 median dark built
from the three frames (their own ``median_image.png`` is truncated). SEP runs in its own
environment (``peers/detect_env.py``) on the same single-channel images, as in
``detect_speed.py``: ``sep.Background`` and ``sep.extract`` at 5 times the global RMS.

With ``--misses``, each matched star the scored detector misses is measured and put down to a
cause (:func:`misses`): at the border, blended with a neighbour, in clutter, too faint for the
fine pass, or dropped by a filter; with how many unconfirmed peaks of the fine image are as
significant as it (what a threshold that took it would let in before the spot filters).

    .venv/bin/python benchmarks/detect_realdata.py [--no-peers] [--misses]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from astropy.io import fits
from astropy.wcs import WCS, FITSFixedWarning
from PIL import Image

from startrack.catalog import load_catalog
from startrack.conventions import from_fits_pixels
from startrack.detect import StarDetector, median_frame, to_single_channel

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
OPENSTARTRACKER = "UBNanosatLab-openstartracker"
IMAGES = {
    "img3.png": OPENSTARTRACKER, "img4.png": OPENSTARTRACKER, "img6.png": OPENSTARTRACKER,
    "crappy.jpg": "smroid-cedar-solve", "orion_trees.jpg": "smroid-cedar-solve",
    "roof.jpg": "smroid-cedar-solve", "tree.jpg": "smroid-cedar-solve", "pleiades.jpg": "smroid-cedar-solve",
}
MATCH_RADIUS_PX = 2.0
CORR_TOLERANCE_PX = 2.0
TOP_N = 30


@dataclass(frozen=True)
class Reference:
    """Reference stars of one image, our pixel convention: astrometry.net's genuine matches
    (``x``, ``y``, shape (K,)) and the Hipparcos stars inside the image (``hip_x``, ``hip_y``)."""

    x: np.ndarray
    y: np.ndarray
    hip_x: np.ndarray
    hip_y: np.ndarray


@dataclass(frozen=True)
class Score:
    """How one detection list compares with a :class:`Reference` (module docstring)."""

    matched: int
    found: int
    top: int
    detections: int
    unconfirmed: int
    point_sources: int
    median_px: float

    @property
    def recall(self) -> float:
        return self.found / self.matched


def load_image(name: str) -> np.ndarray:
    """The image as one plane (colour: R + G + B)."""
    with Image.open(REALDATA / IMAGES[name] / name) as img:
        return to_single_channel(np.asarray(img))


def reference(name: str) -> Reference:
    """astrometry.net's genuine matches and the Hipparcos stars through its WCS."""
    truth = REALDATA / IMAGES[name] / "truth"
    corr = fits.getdata(truth / (Path(name).stem + ".corr"))
    genuine = np.hypot(corr["field_x"] - corr["index_x"], corr["field_y"] - corr["index_y"]) < CORR_TOLERANCE_PX
    x, y = from_fits_pixels(np.asarray(corr["field_x"][genuine], float), np.asarray(corr["field_y"][genuine], float))
    wcs, header = truth_wcs(name)
    hx, hy = _hipparcos_pixels(wcs, int(header["IMAGEW"]), int(header["IMAGEH"]))
    return Reference(x, y, hx, hy)


def truth_wcs(name: str) -> tuple[WCS, fits.Header]:
    """astrometry.net's TAN-SIP solution of image ``name`` (``truth/<image>.wcs``) and its header."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FITSFixedWarning)  # a header without an image
        header = fits.Header.fromfile(REALDATA / IMAGES[name] / "truth" / (Path(name).stem + ".wcs"))
        return WCS(header), header


def _hipparcos_pixels(wcs: WCS, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel positions (0-based) of the Hipparcos stars within 10 deg of the WCS reference point
    that fall inside the image."""
    catalog = load_catalog()
    ra0, dec0 = np.radians(wcs.wcs.crval)
    cos_sep = (np.sin(catalog.dec_rad) * np.sin(dec0)
               + np.cos(catalog.dec_rad) * np.cos(dec0) * np.cos(catalog.ra_rad - ra0))
    near = cos_sep > np.cos(np.radians(10.0))
    px, py = wcs.all_world2pix(np.degrees(catalog.ra_rad[near]), np.degrees(catalog.dec_rad[near]), 0)
    inside = (px > -0.5) & (py > -0.5) & (px < width - 0.5) & (py < height - 0.5)
    return px[inside], py[inside]


def score(x: np.ndarray, y: np.ndarray, ref: Reference, point: np.ndarray | None = None) -> Score:
    """Compare detections (x, y brightest first; ``point``: their point-source flags) with the
    reference stars."""
    if len(x) == 0:
        return Score(ref.x.size, 0, 0, 0, 0, 0, float("nan"))
    d = np.hypot(ref.x[:, None] - x[None], ref.y[:, None] - y[None])
    dh = np.hypot(ref.hip_x[:, None] - x[None], ref.hip_y[:, None] - y[None]) if ref.hip_x.size else \
        np.full((1, len(x)), np.inf)
    found = d.min(axis=1) < MATCH_RADIUS_PX
    nearest = d.argmin(axis=1)
    confirmed = (d.min(axis=0) < MATCH_RADIUS_PX) | (dh.min(axis=0) < MATCH_RADIUS_PX)
    points = int(np.sum(point[nearest[found]])) if point is not None else int(found.sum())
    median = float(np.median(d.min(axis=1)[found])) if found.any() else float("nan")
    return Score(ref.x.size, int(found.sum()), int((d[:, :TOP_N].min(axis=1) < MATCH_RADIUS_PX).sum()), len(x),
                 int((~confirmed).sum()), points, median)


def openstartracker_dark() -> np.ndarray:
    """Huffman 2006 §4.1's median dark of the three openstartracker frames (the fields differ, so
    the median keeps the hot pixels and drops the stars)."""
    return median_frame([load_image(n) for n, folder in IMAGES.items() if folder == OPENSTARTRACKER])


def run_ours(image: np.ndarray, detector: StarDetector, repeats: int = 3) -> tuple[object, float]:
    """Detections and the fastest of ``repeats`` detection times (s)."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        det = detector.detect(image)
        best = min(best, time.perf_counter() - t0)
    return det, best


def run_sep(images: dict[str, np.ndarray]) -> dict[str, tuple[np.ndarray, np.ndarray, float]]:
    """SEP's detections (x, y brightest first) and median time per image, in its environment."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from peers.detect_env import run_peers

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, image in images.items():
            frames, result = Path(tmp) / "frames.npz", Path(tmp) / "out.npz"
            np.savez(frames, frames=image.astype(np.float32)[None], psf_sigma_px=1.0)
            peers = run_peers(frames, result, repeats=3)
            order = np.argsort(-peers["sep_flux"])
            out[name] = (peers["sep_x"][order], peers["sep_y"][order], float(peers["sep_time_s"][0]))
    return out


# --- why a matched star is missed (--misses) ---------------------------------------------------
@dataclass(frozen=True)
class Miss:
    """One matched star the detector missed: where, how significant in the fine image (peak of
    the full-resolution pass's significance within 1 px, :mod:`startrack.detect._fine_pass`) and
    in the binned one, its distances to the border and to the nearest detection, the spread of its
    ring (:func:`startrack.detect._fine_pass.ring_noise_ratio`, 1 on open sky), the tile clutter,
    how many unconfirmed peaks of the fine image are at least as significant (what a threshold
    low enough for it would let in before the spot filters), and the cause it is put down to."""

    x: float
    y: float
    fine_sigma: float
    binned_sigma: float
    edge_px: float
    nearest_px: float
    ring: float
    clutter: float
    competing: int
    cause: str


def significance_maps(image: np.ndarray, detector: StarDetector) -> tuple[np.ndarray, np.ndarray, float, object]:
    """The fine and the binned (full-resolution shape) significance images, the pixel noise and the
    background model, built as the detector builds them (``dark_frame`` applied)."""
    from startrack.detect import _pipeline as pipeline
    from startrack.detect._background import low_side_clipped
    from startrack.detect._fine_pass import fine_significance
    from startrack.detect._smooth import detection_image
    from startrack.detect._threshold import significance

    prepared, _ = pipeline.preprocess(detector, image, detector.dark_frame)
    data, skewed = prepared.data, low_side_clipped(np.asarray(image))
    binned = detection_image(data, detector.binning, detector.kernel, detector.kernel_px, prepared.invalid)
    model = pipeline.background_model(detector, binned, detector.binning, skewed)
    coarse = np.kron(significance(binned, model, detector.binning), np.ones((detector.binning,) * 2))
    h, w = data.shape
    fine = fine_significance(data, prepared.invalid, detector.kernel, detector.kernel_px, detector.tile_px, skewed)
    fine = np.zeros((h, w)) if fine is None else fine
    pad = np.zeros((h, w))
    pad[:coarse.shape[0], :coarse.shape[1]] = coarse[:h, :w]
    return fine, pad, pipeline.pixel_noise(data, model), (data, model)


def _near_max(image: np.ndarray, x: float, y: float, half: int = 1) -> float:
    xi, yi = int(round(x)), int(round(y))
    return float(np.nanmax(image[max(0, yi - half): yi + half + 1, max(0, xi - half): xi + half + 1]))


def misses(image: np.ndarray, detector: StarDetector, det, ref: Reference) -> list[Miss]:
    """The matched stars of ``ref`` that ``det`` (the detector's output) does not hold, each
    with its measurements and cause: *edge* (within 4 px of the border), *blend* (a detection or
    another reference star 2-6 px away took it), *clutter* (a ring over 1.4 that the spot does not
    stand 1.5 times the fine threshold above, :func:`startrack.detect._fine_pass.quiet_surroundings`,
    or a tile clutter over the detector's limit), *faint* (fine significance under the detector's ``fine_sigma``),
    otherwise *filtered* (significant, alone, on open sky, yet a spot filter or a rule of the
    fine pass dropped it)."""
    from scipy.ndimage import maximum_filter

    from startrack.detect._fine_pass import MAX_RING_NOISE, ring_noise_ratio, stands_above_ring

    fine, coarse, noise, (data, model) = significance_maps(image, detector)
    peaks = (fine == maximum_filter(fine, 5)) & (fine > 3.0)
    py, px = np.nonzero(peaks)
    known = np.concatenate([ref.x, ref.hip_x]), np.concatenate([ref.y, ref.hip_y])
    unconfirmed = np.hypot(px[:, None] - known[0][None], py[:, None] - known[1][None]).min(axis=1) >= MATCH_RADIUS_PX
    h, w = data.shape
    out = []
    d = np.hypot(ref.x[:, None] - det.x[None], ref.y[:, None] - det.y[None]) if len(det.x) else None
    for i in range(ref.x.size):
        if d is not None and d[i].min() < MATCH_RADIUS_PX:
            continue
        x, y = float(ref.x[i]), float(ref.y[i])
        others = np.hypot(known[0] - x, known[1] - y)
        nearest = min(float(d[i].min()) if d is not None else np.inf,
                      float(np.min(others[others >= MATCH_RADIUS_PX], initial=np.inf)))
        sig = _near_max(fine, x, y)
        ring = float(ring_noise_ratio(data, np.array([x]), np.array([y]), noise)[0])
        clutter = float(model.clutter_at(np.array([x]), np.array([y]))[0])
        edge = min(x, y, w - 1 - x, h - 1 - y)
        busy = ring > MAX_RING_NOISE and not stands_above_ring(fine, np.array([x]), np.array([y]), np.array([sig]),
                                                               detector.fine_sigma or detector.sigma)[0]
        cause = _cause(detector, edge, nearest, busy, clutter, sig)
        out.append(Miss(x, y, sig, _near_max(coarse, x, y, 2), edge, nearest, ring, clutter,
                        int(np.sum(unconfirmed & (fine[py, px] >= sig))), cause))
    return out


def _cause(detector: StarDetector, edge_px: float, nearest_px: float, busy_ring: bool, clutter: float,
           sig: float) -> str:
    """:func:`misses`'s cause of one miss, the first that applies."""
    if edge_px < 4:
        return "edge"
    if nearest_px < 6:
        return "blend"
    if busy_ring or clutter > (detector.max_clutter or np.inf):
        return "clutter"
    return "faint" if sig < (detector.fine_sigma or detector.sigma) else "filtered"


def print_misses(name: str, found: list[Miss]) -> None:
    for m in found:
        print(f"  {name:<16} miss at ({m.x:6.1f}, {m.y:6.1f}): {m.cause:<8} fine {m.fine_sigma:5.1f} sigma, binned "
              f"{m.binned_sigma:5.1f}, edge {m.edge_px:5.1f} px, nearest {m.nearest_px:6.1f} px, ring {m.ring:4.2f}, "
              f"clutter {m.clutter:4.2f}, unconfirmed peaks as significant {m.competing}")


def row(label: str, s: Score, seconds: float) -> str:
    return (f"{label:<30}{s.matched:>5}{s.found:>6}{s.recall:>7.0%}{s.top:>6}{s.detections:>6}{s.unconfirmed:>7}"
            f"{s.point_sources:>7}{s.median_px:>8.3f}{seconds * 1e3:>8.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-peers", action="store_true", help="skip SEP")
    parser.add_argument("--misses", action="store_true", help="say why each missed matched star is missed")
    args = parser.parse_args(argv)
    if not (REALDATA / "truth.csv").is_file():
        print(f"real-image folder {REALDATA} is absent")
        return 0
    images = {name: load_image(name) for name in IMAGES}
    refs = {name: reference(name) for name in IMAGES}
    dark = openstartracker_dark()
    sep = {} if args.no_peers else run_sep(images)
    print(f"{'image / detector':<30}{'match':>5}{'found':>6}{'recall':>7}{'top30':>6}{'dets':>6}{'unconf':>7}"
          f"{'point':>7}{'med px':>8}{'ms':>8}")
    report = []
    for name, image in images.items():
        det, seconds = run_ours(image, StarDetector())
        print(row(f"{name} startrack", score(det.x, det.y, refs[name], det.is_point_source), seconds))
        scored = StarDetector()
        if IMAGES[name] == OPENSTARTRACKER:
            scored = StarDetector(dark_frame=dark)
            det, seconds = run_ours(image, scored)
            print(row(f"{name} startrack + dark", score(det.x, det.y, refs[name], det.is_point_source), seconds))
        if args.misses:
            report.append((name, misses(image, scored, det, refs[name])))
        if name in sep:
            x, y, seconds = sep[name]
            print(row(f"{name} SEP", score(x, y, refs[name]), seconds))
    print(f"match: astrometry.net's genuine matches; found / recall: detected within {MATCH_RADIUS_PX:g} px; top30: "
          f"among the brightest {TOP_N}; unconf: detections near neither a match nor a Hipparcos star; point: found "
          "stars marked point sources; med px: offset from astrometry.net; ms: fastest of 3 (SEP: median)")
    if report:
        print("\nMissed matched stars (the scored detector: with the dark on the openstartracker frames); sigma: "
              "the fine / binned significance at the star")
        for name, found in report:
            print_misses(name, found)
    return 0


if __name__ == "__main__":
    sys.exit(main())
