"""Catalog-guided measurement: the stars a solution predicts in its image, measured where they must be.

Once an image is solved, every catalog star the solution puts inside the frame has a known
position, to within the fit's residual. A star too faint to stand out of the noise peaks of the
whole frame (a blind detector must search every pixel) can still stand out of the few pixels
where it has to be. This is the predictive centroiding of tracking (Samaan 2002), applied to one
frame after lost-in-space, and the reason astrometry.net's verification scores the stars it
predicts rather than only those it detected (Lang 2010).

The test. Each star is measured in the detector's full-resolution significance image
(:func:`startrack.detect.fine_significance`: the locally flattened, lightly smoothed frame over
its tiled noise): its statistic is the highest significance within the search radius of its
predicted position (:data:`SEARCH_SIGMAS` times the fit's rms residual, within
:data:`SEARCH_PX_RANGE`). The same statistic taken at sky positions far from every predicted
star and every detection gives its distribution where there is no star, measured on the image
itself, so that whatever makes its noise peaks (correlated JPEG noise, lit leaves, gradients,
hot pixels) sets the threshold. With K stars tested, a star is accepted above the sky's
``1 - false_alarms / K`` quantile: ``false_alarms`` (0.1 by default) wrong acceptances are
expected per image at most (a Bonferroni bound on that empirical distribution). Accepted stars
are then centroided in a window about the prediction (:meth:`StarDetector.measure_windows`) and
kept when the centroid lies within the search radius of it.

The stars tested are the catalog stars inside the frame down to the faintest matched star's V
plus :data:`MAG_MARGIN` (and no fainter than the pattern database's catalog, V 9.5 by default),
not already matched nor within :data:`DETECTED_PX` of a detection (a star the detector found, or
a blend with one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..attitude import angle_residuals, solve_wahba
from ..camera import Camera
from ..catalog import load_catalog
from ..errors import InvalidInputError, check_instance, is_real_number, require
from ..frames import radec_roll_from_rotation
from ..results import AttitudeSolution, Detections, StarMatches
from ..units import ARCSEC
from ._database import DatabaseSettings
from ._field_stars import field_stars
from ._image_epoch import DEFAULT_EPOCH_JYEAR
from ._refine import pixel_vectors

if TYPE_CHECKING:
    from ..detect import WindowDetections

DEFAULT_FALSE_ALARMS = 0.1
"""Expected wrong acceptances per image (the test's level, over all the stars tested)."""

MAG_MARGIN = 1.0
"""Stars are tested down to the faintest matched star's V magnitude plus this."""

CONE_MARGIN = 1.05
"""Stars are predicted within this times half the frame's diagonal field of view of the boresight
(no farther: a fitted lens polynomial can fold stars far outside the frame back into it)."""

SEARCH_SIGMAS = 3.0
SEARCH_PX_RANGE = (1.0, 3.0)
"""Search radius about a prediction: 3 times the fit's rms residual, within 1-3 px."""

DETECTED_PX = 3.0
"""A predicted star this close to a detection is not tested (found, or blended with it)."""

SKY_CLEARANCE_PX = 6.0
"""Sky positions are at least this far from every predicted star and detection."""

MAX_SKY_SAMPLES = 1_000_000
"""At most this many sky positions, on a regular grid (every pixel of a frame up to 1 Mpx)."""

WINDOW_MARGIN_PX = 2
"""The centroid window reaches this far past the search radius."""

MIN_SIGMA_PX = 0.01
"""Floor of a star's centroid error in the weighted refit (px)."""

WINDOW_SIGMA = 1.5
"""Detection threshold inside the centroid windows (noise units of the window's ring)."""


@dataclass(frozen=True)
class GuidedStars:
    """Catalog stars measured at the positions a solution predicts (:mod:`startrack.identify._guided`).

    Attributes
    ----------
    detections : Detections
        Their measurements (G rows, brightest catalog star first): centroid (our pixel
        convention), ``sigma_px``, flux and spot shape from the centroid windows.
    catalog_rows : ndarray of int, shape (G,)
        Rows of :func:`startrack.catalog.load_catalog`.
    predicted_x, predicted_y : ndarray, shape (G,)
        Where the solution put them (px).
    significance : ndarray, shape (G,)
        The test statistic (noise units of the significance image).
    threshold : float
        The acceptance threshold (noise units); inf when nothing could be tested.
    tested : int
        Stars tested (K).
    sky_samples : int
        Sky positions that gave the threshold.
    search_px : float
        Search radius about each prediction (px).
    """

    detections: Detections = field(default_factory=Detections)
    catalog_rows: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    predicted_x: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    predicted_y: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    significance: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    threshold: float = math.inf
    tested: int = 0
    sky_samples: int = 0
    search_px: float = 0.0

    def __len__(self) -> int:
        return len(self.detections)

    def take(self, index) -> GuidedStars:
        """A subset (or reordering) of the stars, by index array or boolean mask."""
        return replace(self, detections=self.detections.take(index), catalog_rows=self.catalog_rows[index],
                       predicted_x=self.predicted_x[index], predicted_y=self.predicted_y[index],
                       significance=self.significance[index])


def guided_stars(image: NDArray, solution: AttitudeSolution, detections: Detections | None = None, *,
                 detector=None, false_alarms: float = DEFAULT_FALSE_ALARMS) -> GuidedStars:
    """Measure the catalog stars a solution predicts in its image and the detector missed.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, C)
        The solved image, raw counts.
    solution : AttitudeSolution
        A solved solution of that image, with its camera.
    detections : Detections, optional
        The image's detections (default ``solution.detections``, which :func:`startrack.solve_image` sets).
    detector : startrack.detect.StarDetector, optional
        The detector's settings (dark frame, kernel, tile size); default the default detector's.
    false_alarms : float
        Expected wrong acceptances per image, in (0, 1].

    Returns
    -------
    GuidedStars
        Empty when the image has no noise to test against or no star to test.

    Raises
    ------
    InvalidInputError
        An unsolved solution, no detections, another image size, or ``false_alarms`` outside (0, 1].
    """
    from ..detect import StarDetector

    detector = StarDetector() if detector is None else check_instance(detector, StarDetector, "detector")
    found, camera = _checked(image, solution, detections, false_alarms)
    snr = _significance(image, detector)
    if snr is None:
        return GuidedStars()
    matched = np.searchsorted(load_catalog().hip, solution.matches.hip)  # catalog rows (it is sorted by HIP)
    rows, px, py = _predicted(solution, camera, matched)
    search = float(np.clip(SEARCH_SIGMAS * _rms_residual_px(solution, camera), *SEARCH_PX_RANGE))
    peak = _disk_maximum(snr, search)
    sky = _sky_values(peak, np.concatenate([px, found.x]), np.concatenate([py, found.y]))
    test = _to_test(rows, px, py, matched, found)
    tested = int(test.sum())
    threshold = _threshold(sky, false_alarms, tested) if tested else math.inf
    stat = peak[np.rint(py).astype(np.int64), np.rint(px).astype(np.int64)].astype(np.float64)
    accepted = np.flatnonzero(test & (stat > threshold))
    windows = _centroids(detector, image, px[accepted], py[accepted], search)
    kept = accepted[windows.window_index]
    return GuidedStars(detections=windows.detections, catalog_rows=rows[kept], predicted_x=px[kept],
                       predicted_y=py[kept], significance=stat[kept], threshold=threshold, tested=tested,
                       sky_samples=int(sky.size), search_px=search)


def _significance(image: NDArray, detector) -> NDArray[np.float32] | None:
    """The detector's full-resolution significance image of ``image`` (its dark frame and
    denoising applied), shape (H, W); None for a frame without noise."""
    from ..detect import fine_significance, low_side_clipped, preprocess

    prepared, _ = preprocess(detector, image, detector.dark_frame)
    return fine_significance(prepared.data, prepared.invalid, detector.kernel, detector.kernel_px,
                             detector.tile_px, low_side_clipped(np.asarray(image)))


def _checked(image: NDArray, solution: AttitudeSolution, detections: Detections | None,
             false_alarms: float) -> tuple[Detections, Camera]:
    """The detections and the camera of a valid call (:func:`guided_stars`)."""
    check_instance(solution, AttitudeSolution, "solution")
    if not solution.solved or solution.camera is None or solution.rot_cam_from_icrs is None:
        raise InvalidInputError(f"solution must be solved (with its camera), got status {solution.status.value!r}")
    found = solution.detections if detections is None else check_instance(detections, Detections, "detections")
    if found is None:
        raise InvalidInputError("detections must be given when the solution has none (solve_stars does not keep them)")
    shape = np.shape(image)
    camera = solution.camera
    if len(shape) not in (2, 3) or shape[:2] != (camera.height, camera.width):
        raise InvalidInputError(f"image must be the solved {camera.width} x {camera.height} px frame, "
                                f"got shape {shape}")
    if not (is_real_number(false_alarms) and 0 < false_alarms <= 1):
        raise InvalidInputError(f"false_alarms must be a number in (0, 1], got {false_alarms!r}")
    return found, camera


def _rms_residual_px(solution: AttitudeSolution, camera: Camera) -> float:
    """The fit's rms residual in pixels (its residuals are arcsec)."""
    return float(np.sqrt(np.mean(np.square(solution.residuals_arcsec)))) / camera.pixel_scale_arcsec


def _predicted(solution: AttitudeSolution, camera: Camera, matched: NDArray[np.int64]
               ) -> tuple[NDArray[np.int64], NDArray, NDArray]:
    """Catalog rows (brightest first) and pixel positions (x, y) of the stars down to the
    faintest matched star's (``matched``: catalog rows) V plus :data:`MAG_MARGIN` that the
    solution puts inside the frame, at least a pixel from its edge."""
    catalog = load_catalog()
    matched_mag = catalog.v_mag[matched]
    if not np.isfinite(matched_mag).any():
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0)
    epoch = solution.epoch_jyear if math.isfinite(solution.epoch_jyear) else DEFAULT_EPOCH_JYEAR
    stars = field_stars(DatabaseSettings().max_mag, epoch)  # the solver's own set (loaded, cached once)
    matrix = require(solution.rot_cam_from_icrs, "the solution's attitude").as_matrix()
    cone_rad = CONE_MARGIN * math.radians(camera.fov_diagonal_deg) / 2.0
    near = np.sort(stars.near(matrix[2], cone_rad))  # brightest first
    near = near[catalog.v_mag[stars.rows[near]] <= float(np.nanmax(matched_mag)) + MAG_MARGIN]
    px, py = camera.vector_to_pixel(stars.vectors[near] @ matrix.T)
    inside = np.flatnonzero(np.isfinite(px) & np.isfinite(py) & camera.in_image(px, py, margin_px=1.0))
    return stars.rows[near[inside]], px[inside], py[inside]


def _to_test(rows: NDArray, px: NDArray, py: NDArray, matched: NDArray, found: Detections) -> NDArray[np.bool_]:
    """Shape (K,): which predicted stars (catalog ``rows`` at px, py) to test: not among the
    ``matched`` rows, and no detection within :data:`DETECTED_PX`."""
    test = ~np.isin(rows, matched)
    if len(found) and rows.size:
        distance, _ = cKDTree(np.column_stack([found.x, found.y])).query(np.column_stack([px, py]))
        test &= distance > DETECTED_PX
    return test


def _disk_maximum(snr: NDArray, radius_px: float) -> NDArray[np.float32]:
    """Shape (H, W): the largest value of ``snr`` within ``radius_px`` of each pixel (NaN as -inf).

    The disk of offsets (dx, dy) with dx^2 + dy^2 <= r^2 is the union, over k = 0 .. floor(r), of
    the rectangles |dy| <= k, |dx| <= floor(sqrt(r^2 - k^2)); each rectangle's maximum is two
    one-dimensional running maxima (:func:`_running_max`), much cheaper than the disk footprint's."""
    values = np.where(np.isnan(snr), -np.inf, snr).astype(np.float32)
    out = np.full_like(values, -np.inf)
    for k in range(int(math.floor(radius_px)) + 1):
        half_x = int(math.floor(math.sqrt(radius_px**2 - k**2)))
        np.maximum(out, _running_max(_running_max(values, k, axis=0), half_x, axis=1), out=out)
    return out


def _running_max(values: NDArray, half: int, axis: int) -> NDArray:
    """The largest of each value and its ``half`` neighbours on either side along ``axis`` (-inf
    beyond the edges), by shifted maxima: a few whole-array passes for the 1-3 px of a search
    radius, where scipy's running maximum walks the columns one by one."""
    out = values.copy()
    for shift in range(1, half + 1):
        ahead = [slice(None)] * values.ndim
        behind = [slice(None)] * values.ndim
        ahead[axis], behind[axis] = slice(shift, None), slice(None, -shift)
        np.maximum(out[tuple(ahead)], values[tuple(behind)], out=out[tuple(ahead)])
        np.maximum(out[tuple(behind)], values[tuple(ahead)], out=out[tuple(behind)])
    return out


def _sky_values(peak: NDArray, x: NDArray, y: NDArray) -> NDArray[np.float32]:
    """The statistic at sky positions: a regular grid of at most :data:`MAX_SKY_SAMPLES` pixels,
    less those within :data:`SKY_CLEARANCE_PX` (a square) of the positions (x, y)."""
    h, w = peak.shape
    occupied = np.zeros((h, w), dtype=bool)
    inside = (x > -0.5) & (y > -0.5) & (x < w - 0.5) & (y < h - 0.5)
    clear = int(SKY_CLEARANCE_PX)
    for i, j in zip(np.rint(y[inside]).astype(np.int64).tolist(), np.rint(x[inside]).astype(np.int64).tolist(),
                    strict=True):  # a few hundred squares: cheaper than filtering the whole frame
        occupied[max(i - clear, 0): i + clear + 1, max(j - clear, 0): j + clear + 1] = True
    step = max(1, math.ceil(math.sqrt(h * w / MAX_SKY_SAMPLES)))
    values = peak[::step, ::step][~occupied[::step, ::step]]
    return values[np.isfinite(values)]


def _threshold(sky: NDArray, false_alarms: float, tested: int) -> float:
    """The sky's ``1 - false_alarms / tested`` quantile (``tested`` >= 1; an order statistic at
    or above it); inf when the sky has too few samples to tell (fewer than ``tested / false_alarms``)."""
    rank = math.ceil(sky.size * (1.0 - false_alarms / tested))
    if rank >= sky.size:
        return math.inf
    return float(np.partition(sky, rank)[rank])


def _centroids(detector, image: NDArray, x: NDArray, y: NDArray, search_px: float) -> WindowDetections:
    """Centroids in windows about the accepted predictions (x, y), kept when within
    ``search_px`` of them. The acceptance is the test's; the windows' own detection threshold is
    set low (:data:`WINDOW_SIGMA`) so that it does not overrule it."""
    from ..detect import WindowDetections

    if x.size == 0:
        return WindowDetections()
    half = math.ceil(search_px) + WINDOW_MARGIN_PX
    windows = replace(detector, sigma=WINDOW_SIGMA, grow_sigma=WINDOW_SIGMA).measure_windows(image, x, y, half)
    det, index = windows.detections, windows.window_index
    near = np.flatnonzero(np.hypot(det.x - x[index], det.y - y[index]) <= search_px)
    order = near[np.argsort(index[near], kind="stable")]  # back to the predictions' order: brightest first
    return WindowDetections(det.take(order), index[order])


def with_guided_stars(solution: AttitudeSolution, guided: GuidedStars, detections: Detections | None = None
                      ) -> AttitudeSolution:
    """The solution refitted on its matched stars and the guided ones.

    The guided stars become the last ``len(guided)`` rows of the solution's ``detections``
    (``point_quality`` NaN: not measured) and of its ``matches``; the attitude is the Wahba
    optimum of all of them on the solution's camera, each star weighted by its centroid's
    ``sigma_px`` (:func:`_weighted_fit`), with the QUEST covariance; ``guided_stars`` counts them.

    Parameters
    ----------
    solution : AttitudeSolution
        A solved solution.
    guided : GuidedStars
        From :func:`guided_stars` on the solution's image.
    detections : Detections, optional
        The detections ``solution.matches.det_index`` indexes (default ``solution.detections``).
    """
    found = require(solution.detections if detections is None else detections, "the solution's detections")
    camera = require(solution.camera, "the solution's camera")
    extra = pixel_vectors(camera, guided.detections.x, guided.detections.y)
    guided = guided.take(np.isfinite(extra).all(axis=1))  # where a fitted wide lens cannot be inverted: left out
    if len(guided) == 0:
        return replace(solution, detections=found)
    epoch = solution.epoch_jyear if math.isfinite(solution.epoch_jyear) else DEFAULT_EPOCH_JYEAR
    catalog = load_catalog()
    det = _appended(found, guided)
    index = np.concatenate([solution.matches.det_index, len(found) + np.arange(len(guided))])
    reference = np.concatenate([solution.matches.cat_vectors, catalog.take(guided.catalog_rows).vectors(epoch)])
    observed = pixel_vectors(camera, det.x[index], det.y[index])
    usable = np.isfinite(observed).all(axis=1)  # all of a solve's; the guided ones are checked above
    hip = np.concatenate([solution.matches.hip, catalog.hip[guided.catalog_rows]])[usable]
    index, reference, observed = index[usable], reference[usable], observed[usable]
    floor_px = _rms_residual_px(solution, camera)
    rotation, covariance, residual_rad = _weighted_fit(observed, reference,
                                                       _sigma_rad(det.sigma_px[index], camera, floor_px))
    ra, dec, roll = radec_roll_from_rotation(rotation)
    matches = StarMatches(status=solution.matches.status, det_index=index.astype(np.int64), hip=hip.astype(np.int64),
                          cat_vectors=reference, false_match_prob=solution.matches.false_match_prob)
    return replace(solution, rot_cam_from_icrs=rotation, covariance_rad2=covariance,
                   ra_deg=math.degrees(ra), dec_deg=math.degrees(dec), roll_deg=math.degrees(roll), matches=matches,
                   residuals_arcsec=residual_rad / ARCSEC, detections=det, guided_stars=len(guided))


def _sigma_rad(sigma_px: NDArray, camera: Camera, floor_px: float) -> NDArray[np.float64]:
    """Each star's direction error (rad): its centroid's ``sigma_px``, but at least ``floor_px``
    (the solve's own rms residual: what its stars scatter by, whatever their centroids claim) and
    :data:`MIN_SIGMA_PX`; a centroider's unknown sigma counts as the floor."""
    sigma = np.nan_to_num(np.asarray(sigma_px, dtype=np.float64), nan=0.0, posinf=0.0)
    return np.maximum(sigma, max(floor_px, MIN_SIGMA_PX)) / math.sqrt(camera.fx * camera.fy)


def _weighted_fit(observed: NDArray, reference: NDArray, sigma_rad: NDArray
                  ) -> tuple[Rotation, NDArray[np.float64], NDArray[np.float64]]:
    """The Wahba optimum with weights 1 / sigma^2 (q-method) and its QUEST covariance, scaled by
    the fit's Birge ratio when its residuals exceed the sigmas (chi-square over 2N - 3 degrees of
    freedom: two per direction, three for the attitude), and the residuals (rad).

    Faint stars centroid several times worse than bright ones: weighted equally, as the
    lost-in-space fit weights its (brighter) matches, the guided stars made the attitude worse
    on simulated frames (``docs/identification.md``)."""
    result = solve_wahba(observed, reference, sigma_rad=sigma_rad, method="qmethod")
    rotation = require(result.rotation, "the fit of a solved frame's stars")
    residual_rad = angle_residuals(rotation, observed, reference)
    birge = float(np.sum((residual_rad / sigma_rad) ** 2)) / max(2 * len(observed) - 3, 1)
    return rotation, require(result.covariance_rad2, "the fit's covariance") * max(birge, 1.0), residual_rad


def _appended(found: Detections, guided: GuidedStars) -> Detections:
    """``found`` with the guided stars' measurements as its last rows."""
    extra = guided.detections
    quality = None if found.point_quality is None else \
        np.concatenate([found.point_quality, np.full(len(extra), np.nan)])
    columns = ("x", "y", "flux", "sigma_px", "area_px", "peak", "elongation")
    return Detections(**{k: np.concatenate([getattr(found, k), getattr(extra, k)]) for k in columns},
                      background=found.background, noise=found.noise, width=found.width, height=found.height,
                      point_quality=quality)
