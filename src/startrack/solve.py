"""Lost-in-space solving: a star list or an image in, an :class:`AttitudeSolution` out.

This module only orchestrates: it validates the input, picks the pattern database for the field
of view, calls the matcher (:mod:`startrack.identify`), refines the match on all stars, and
computes the QUEST attitude with its covariance (:mod:`startrack.attitude`).
"""

from __future__ import annotations

import functools
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from .camera import Camera
from .catalog import load_catalog
from .errors import InvalidInputError, require
from .identify import (
    DEFAULT_EPOCH_JYEAR,
    DEFAULT_FOV_RANGE_DEG,
    FOV_DEG_TOLERANCE,
    MAX_FOV_DEG,
    MIN_FOV_DEG,
    REMATCH_RADIUS_PX,
    Candidate,
    FieldStars,
    MatcherOptionsBase,
    MethodName,
    Parity,
    SolveRequest,
    build_request,
    check_fov_deg,
    check_options,
    epoch_jyear,
    pixel_vectors,
    prepare_matcher,
    resolve_epoch,
    settle_matches,
    solution_terms,
    stated_search_range,
)
from .identify import star_arrays as _star_arrays  # noqa: F401 (startrack.multihead checks heads with it)
from .results import AttitudeSolution, Detections, StarMatches, Status
from .units import ARCSEC

if TYPE_CHECKING:
    from astropy.time import Time

    from .io import Image

__all__ = ["DEFAULT_EPOCH_JYEAR", "DEFAULT_FOV_RANGE_DEG", "FOV_DEG_TOLERANCE", "MAX_FOV_DEG", "MIN_FOV_DEG",
           "check_fov_deg", "epoch_jyear", "solve_image", "solve_stars"]


MIN_SOLUTION_STARS = 3
"""A solution rests on at least this many matched stars after the final fit: two give an exact
attitude that nothing checks. A verified candidate whose fit keeps fewer (stars laid out along a
line, which the false-match test, made for stars strewn over the image, overrates) is no match."""


MAX_SOLUTION_RESIDUAL_PX = REMATCH_RADIUS_PX
"""... and they lie within this many pixels rms of where its attitude puts them, the radius within
which the final fit matched them: a fit that bends its lens to lay any line of stars on the
catalog (focal length, aspect and k1 free) leaves the rigid attitude tens of pixels off them."""


def _solution(problem: SolveRequest, stars: FieldStars, cand: Candidate, t0: float,
              fov_source: str = "") -> AttitudeSolution:
    """The solution from a verified candidate: refined fit, then the Wahba attitude of all matched
    stars (Davenport's q-method: the same optimum as QUEST) with the QUEST measurement-model
    covariance (Huffman 2006 §6.1.3), residuals and RA / Dec / roll, in one compiled call
    (:func:`.identify.refine.solution_terms`; the solvers and the covariance are in
    :mod:`startrack.attitude`). The attitude is a rotation matrix inside; the one Rotation is the
    solution's. A mirror image's candidate has a ``mirrored`` camera (:mod:`.identify._parity`),
    which the fit and the solution keep. ``fov_source``: the solution's
    :attr:`~startrack.results.AttitudeSolution.fov_source`."""
    fit = settle_matches(problem.x, problem.y, stars, cand, problem.focal_range, fit_aspect=problem.fit_aspect)
    camera, img, rows, ref, res_px = fit.camera, fit.image_index, fit.catalog_rows, fit.ref_icrs, fit.residual_px
    observed = pixel_vectors(camera, problem.x[img], problem.y[img])
    if not math.isfinite(float(observed.sum())):  # a star where a fitted wide lens cannot be inverted: left out
        usable = np.isfinite(observed).all(axis=1)
        img, rows, ref, res_px, observed = img[usable], rows[usable], ref[usable], res_px[usable], observed[usable]
    if len(img) < MIN_SOLUTION_STARS:
        return _not_held(problem, t0, f"the final fit kept {len(img)} of its stars (at least {MIN_SOLUTION_STARS} "
                                      "needed)", fov_source)
    sigma_rad = max(math.sqrt(float(res_px @ res_px) / len(img)), 0.05) / math.sqrt(camera.fx * camera.fy)
    quat, _, residual_rad, covariance, (ra, dec, roll) = solution_terms(observed, ref, sigma_rad)  # >= 3 stars
    rms_px = math.sqrt(float(residual_rad @ residual_rad) / len(img) * camera.fx * camera.fy)
    if not rms_px <= MAX_SOLUTION_RESIDUAL_PX:
        return _not_held(problem, t0, f"its {len(img)} stars lie {rms_px:.3g} px rms from where its attitude puts "
                                      f"them (at most {MAX_SOLUTION_RESIDUAL_PX:g} px)", fov_source)
    matches = StarMatches(status=Status.OK, det_index=problem.rows[img].astype(np.int64),
                          hip=_hip()[rows].astype(np.int64), cat_vectors=ref,
                          false_match_prob=cand.false_match_prob)
    return AttitudeSolution(
        status=Status.OK, rot_cam_from_icrs=Rotation.from_quat(quat), covariance_rad2=covariance,
        ra_deg=math.degrees(ra), dec_deg=math.degrees(dec), roll_deg=math.degrees(roll),
        fov_deg=camera.fov_deg, camera=camera, matches=matches, residuals_arcsec=residual_rad / ARCSEC,
        false_match_prob=cand.false_match_prob, solve_time_s=time.perf_counter() - t0,
        epoch_jyear=problem.epoch.jyear, epoch_source=problem.epoch.source, fov_source=fov_source)


def _not_held(problem: SolveRequest, t0: float, why: str, fov_source: str) -> AttitudeSolution:
    """No match: the matcher's verified candidate did not survive the final fit, ``why``."""
    return _failed(problem, Status.NO_MATCH, f"a verified match did not hold: {why}", time.perf_counter() - t0,
                   fov_source)


def _failed(problem: SolveRequest, status: Status, reason: str, solve_time_s: float,
            fov_source: str) -> AttitudeSolution:
    """A solve of ``problem`` that found no attitude: ``status`` and ``reason``, after ``solve_time_s``
    (s), with the request's epoch and the given ``fov_source``."""
    return AttitudeSolution(status=status, reason=reason, solve_time_s=solve_time_s, epoch_jyear=problem.epoch.jyear,
                            epoch_source=problem.epoch.source, fov_source=fov_source)


def _hip() -> np.ndarray:
    """Hipparcos numbers of the catalog's rows (:func:`startrack.catalog.load_catalog`)."""
    return load_catalog().hip


def _run(problem: SolveRequest, method: MethodName, options: MatcherOptionsBase | None,
         fov_source: str) -> AttitudeSolution:
    """Run the named matcher on a validated request and build the solution (or the failure), its
    :attr:`~startrack.results.AttitudeSolution.fov_source` ``fov_source``."""
    if (known := _failure_before_search(problem, method)) is not None:
        return _failed(problem, *known, 0.0, fov_source)
    matcher, stars = prepare_matcher(method, problem)  # loads (or builds) the database first
    t0 = time.perf_counter()
    outcome = matcher(options)
    if outcome.candidate is None:
        reason = outcome.reason + (_no_match_hints(problem, method) if outcome.status is Status.NO_MATCH else "")
        return _failed(problem, outcome.status, reason, time.perf_counter() - t0, fov_source)
    return _solution(problem, stars, outcome.candidate, t0, fov_source)


def _no_match_hints(problem: SolveRequest, method: MethodName) -> str:
    """What a search that found nothing took as known that the user may have got wrong, for its
    reason: a calibrated camera or a field of view given (searched within ``FOV_DEG_TOLERANCE``:
    a range of exactly that span), and, for the matcher that can search mirror images, the
    image's parity."""
    hints = []
    lo, hi = problem.fov_range_deg
    if problem.focal_range is None:
        hints.append("the camera's focal length was taken as calibrated")
    elif math.isclose(hi / lo, (1 + FOV_DEG_TOLERANCE) / (1 - FOV_DEG_TOLERANCE), rel_tol=1e-9):
        hints.append(f"the field of view was searched within {FOV_DEG_TOLERANCE:.0%} of the one given; if it is "
                     "less sure, give a range or none")
    if problem.parity == "normal" and method == "quads":
        hints.append("a mirror image (flipped, or y up) needs parity 'either'")
    if (narrow := _narrow_field_hint(problem.camera, hi)) is not None:
        hints.append(narrow)
    return "".join(f"; {hint}" for hint in hints)


def _failure_before_search(problem: SolveRequest, method: MethodName) -> tuple[Status, str] | None:
    """The status and reason of a lost-in-space solve that cannot succeed, known before its
    database is loaded, or built (about 30 s for a new narrow field): fewer than 4 stars, or a
    field too sparse in catalog stars (:func:`too_sparse_to_solve`). None otherwise, and for the
    overlay matcher (its prior attitude needs no database)."""
    if method == "overlay":
        return None
    if problem.x.size < 4:
        return Status.TOO_FEW_STARS, f"lost-in-space identification needs at least 4 stars, got {problem.x.size}"
    width_deg, height_deg = _field_deg(problem.camera, problem.fov_range_deg[1])
    if too_sparse_to_solve(width_deg, height_deg / width_deg):
        return Status.NO_MATCH, f"not searched: {_sparse_field_words(width_deg, height_deg)}"
    return None


FEW_CATALOG_STARS = 20.0
"""A field that holds fewer Hipparcos stars than this on average gets a hint with its failure
(:func:`_narrow_field_hint`): a telescope's narrow field, whose stars are mostly fainter than
the catalog."""

MIN_CATALOG_STARS = 1.5
"""A lost-in-space solve of a field that holds fewer Hipparcos stars than this on average, at the
widest field searched, fails at once (:func:`too_sparse_to_solve`). A solution confirms a
pattern of 4 stars with at least 2 more (``identify._confirm.MIN_EXTRA_MATCHES``); of 200,000
random fields of 0.5 deg2, which hold 1.43 stars on average, 99 % held at most 4 and 99.9 % at
most 6 (a 0.72 deg square field holds 1.5)."""

SKY_DEG2 = 4.0 * math.pi * math.degrees(1.0) ** 2
"""The whole sky in square degrees (41,253)."""


def expected_catalog_stars(width_deg: float, height_deg: float) -> float:
    """How many Hipparcos stars a field of ``width_deg`` x ``height_deg`` holds on average over
    the sky (2.86 per deg2; small fields, taken as flat)."""
    return len(load_catalog().hip) / SKY_DEG2 * width_deg * height_deg


def too_sparse_to_solve(fov_deg: float, height_ratio: float = 1.0) -> bool:
    """Whether a field ``fov_deg`` wide (horizontal, deg) and ``height_ratio`` times as high holds
    fewer than :data:`MIN_CATALOG_STARS` Hipparcos stars on average: too few for a lost-in-space
    solve almost anywhere on the sky, so that no pattern database is built for it."""
    return expected_catalog_stars(fov_deg, fov_deg * height_ratio) < MIN_CATALOG_STARS


def _field_deg(camera: Camera, fov_deg: float) -> tuple[float, float]:
    """Width and height (deg) of a field ``fov_deg`` wide on ``camera``'s image (its aspect ratio
    and pixel aspect)."""
    return fov_deg, fov_deg * (camera.height / camera.width) * camera.pixel_aspect


def _narrow_field_hint(camera: Camera, fov_deg: float) -> str | None:
    """How many Hipparcos stars a field of ``fov_deg`` (horizontal, deg) on ``camera``'s image
    (its aspect ratio) holds on average, when fewer than :data:`FEW_CATALOG_STARS`: why a narrow
    field did not solve. None for a wider field."""
    width_deg, height_deg = _field_deg(camera, fov_deg)
    if expected_catalog_stars(width_deg, height_deg) >= FEW_CATALOG_STARS:
        return None
    return _sparse_field_words(width_deg, height_deg)


def _sparse_field_words(width_deg: float, height_deg: float) -> str:
    """The hint of :func:`_narrow_field_hint` for a field of ``width_deg`` x ``height_deg``."""
    expected = expected_catalog_stars(width_deg, height_deg)
    return (f"a field of {width_deg:.3g} x {height_deg:.3g} deg holds {expected:.0f} Hipparcos stars on average "
            "(the catalog is complete to about V 7.3; fainter stars, most of a telescope's image, are not in it)")


def _check_parity_method(request: SolveRequest, method: MethodName) -> None:
    """Only the "quads" matcher searches mirror images (:mod:`.identify._parity`)."""
    if request.parity != "normal" and method != "quads":
        raise InvalidInputError(f"parity {request.parity!r} needs method 'quads' (the {method!r} matcher "
                                "searches the image as given only); give parity='normal' or method='quads'")


def _check_prior(prior_rot_cam_from_icrs, prior_sigma_deg) -> float:
    if prior_rot_cam_from_icrs is not None and not isinstance(prior_rot_cam_from_icrs, Rotation):
        raise InvalidInputError("prior_rot_cam_from_icrs must be a scipy Rotation, "
                                f"got {type(prior_rot_cam_from_icrs).__name__}")
    try:
        sigma = float(prior_sigma_deg)
    except (TypeError, ValueError):
        sigma = math.nan
    if not (math.isfinite(sigma) and sigma > 0):
        raise InvalidInputError(f"prior_sigma_deg must be a positive number of degrees, got {prior_sigma_deg!r}")
    return sigma


def solve_stars(x: ArrayLike, y: ArrayLike, *, width: int | None = None, height: int | None = None,
                fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                camera: Camera | None = None, flux: ArrayLike | None = None, epoch: Time | float | None = None,
                method: MethodName = "quads", options: MatcherOptionsBase | None = None,
                prior_rot_cam_from_icrs: Rotation | None = None, prior_sigma_deg: float = 1.0,
                pixel_aspect: float | tuple[float, float] | None = None,
                parity: Parity | None = None) -> AttitudeSolution:
    """Lost-in-space attitude from a list of star centroids.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Star centroids in our pixel convention (0-based pixel centres, x = column), brightest
        first (or give ``flux`` and they are sorted by it).
    width, height : int
        Image size in pixels (taken from ``camera`` when one is given).
    fov_deg : float, optional
        Horizontal field of view (deg, :data:`MIN_FOV_DEG` to :data:`MAX_FOV_DEG`: 0.5 to 150),
        trusted to +-3 % and refined.
    fov_range_deg : (float, float), optional
        Range of horizontal fields of view to search (deg, within the same limits); default
        (3, 100) when neither is given.
    camera : Camera, optional
        A calibrated camera (focal lengths, principal point, distortion): the focal length is
        then fixed.
    flux : array_like, shape (N,), optional
        Brightness of each star, to order them.
    epoch : astropy.time.Time or float, optional
        Epoch of the catalog positions (Julian year, TDB); default J2000.0. The solution says
        which it used (``epoch_jyear``, ``epoch_source``).
    method : MethodName
        The matcher (:data:`startrack.identify._registry.MethodName`; another name is refused
        with the valid ones): "quads", four-star patterns
        (the default; any FOV knowledge); the seeds' matchers on the star-pair directory, which
        need a FOV known to 5 % or a camera ("pyramid", "angle", "triangle-planar",
        "triangle-spherical", "nvertex-3", "nvertex-4", "nvertex-5", "van-bezooijen"); or
        "overlay", which needs a prior attitude. See ``docs/identification.md``.
    options : MatcherOptionsBase, optional
        Settings of the chosen matcher, an instance of its subclass of
        :class:`startrack.identify._options_base.MatcherOptionsBase` (``MatcherOptions`` for
        "quads", ``PyramidOptions`` for "pyramid", and so on: ``registry.OPTIONS[method]``, or
        ``registry.options_for(method, ...)``); another matcher's class is refused, naming the
        method, the class given and the one expected.
    prior_rot_cam_from_icrs : Rotation, optional
        Prior attitude for the "overlay" matcher.
    prior_sigma_deg : float
        Its 1-sigma uncertainty per axis (degrees, up to 10).
    pixel_aspect : float or (float, float), optional
        Height of a pixel on the sky over its width (fx / fy; 1 for square pixels), or a range
        (low, high) to search for it (slower: each aspect is a search). Not given: square pixels
        are assumed in the search and the aspect is fitted in the final solution. Not with a
        camera, which has its own. See :mod:`startrack.identify._request`.
    parity : {"normal", "mirrored", "either"}, optional
        Whether the stars are those of a mirror image of the sky (:mod:`startrack.identify._parity`):
        default "normal", or the camera's when a ``mirrored`` camera is given; "either" searches
        both (with the "quads" matcher only). A mirror image's solution has a ``mirrored`` camera.

    Returns
    -------
    AttitudeSolution
        ``status`` OK with the attitude, covariance, matches and residuals; otherwise
        TOO_FEW_STARS, NO_MATCH or TIMEOUT with a reason. ``solve_time_s`` excludes loading the
        pattern database (done once per process).

    Raises
    ------
    InvalidInputError
        For NaN, masked or out-of-frame coordinates, two stars at exactly the same position (a
        list with a star twice; :func:`solve_image` drops such repeats itself), a bad image size,
        field of view, pixel aspect, epoch, camera, options or prior.
    """
    method = check_options(method, options)
    sigma = _check_prior(prior_rot_cam_from_icrs, prior_sigma_deg)
    request = build_request(x, y, width=width, height=height, fov_deg=fov_deg, fov_range_deg=fov_range_deg,
                            camera=camera, flux=flux, epoch=resolve_epoch(epoch), pixel_aspect=pixel_aspect,
                            parity=parity)
    _check_parity_method(request, method)
    if prior_rot_cam_from_icrs is not None or sigma != request.prior_sigma_deg:  # else the defaults hold
        request = replace(request, prior_rot=prior_rot_cam_from_icrs, prior_sigma_deg=sigma)
    return _run(request, method, options, _given_fov_source(fov_deg, fov_range_deg, camera))


SEARCH_CELLS, SPOTS_PER_TURN = 6, 2
"""The search order takes turns between the cells of a 6 x 6 grid over the image, two spots of a
cell at a time (:func:`spread_rounds`)."""


def search_order(found) -> np.ndarray:
    """Indices of detections in the order the solver should see them: point sources first
    (:attr:`startrack.results.Detections.is_point_source`; the spots the detector found extended
    or elongated last), each group in rounds over the image's cells (:func:`spread_rounds`),
    brightest first within a round, and a spot at exactly the position of an earlier one left
    out (it would only repeat it)."""
    index = np.argsort(~found.is_point_source, kind="stable")
    x, y = found.x[index], found.y[index]
    by_position = np.lexsort((y, x))  # stable: a repeated position's first occurrence comes first
    again = (x[by_position[1:]] == x[by_position[:-1]]) & (y[by_position[1:]] == y[by_position[:-1]])
    keep = np.ones(index.size, dtype=bool)
    keep[by_position[1:][again]] = False
    index = index[keep]
    width, height = found.width or np.max(found.x, initial=0) + 1, found.height or np.max(found.y, initial=0) + 1
    rounds = spread_rounds(found.x[index], found.y[index], width, height)
    return index[np.lexsort((rounds, ~found.is_point_source[index]))]  # stable within a round


def spread_rounds(x: NDArray, y: NDArray, width: float, height: float, cells: int = SEARCH_CELLS,
                  per_turn: int = SPOTS_PER_TURN) -> NDArray[np.int64]:
    """Round of each of N spots (shape (N,), in the given order, brightest first): 0 for the
    first ``per_turn`` spots of their cell of a ``cells`` x ``cells`` grid over the ``width`` x
    ``height`` px image, 1 for the next ``per_turn``, and so on.

    The solver forms its patterns from the first spots it sees (20, :mod:`.identify`). Taken
    by brightness alone, those can all lie in one small part of the frame, and there they are
    seldom all stars: the strokes of a saturated caption or watermark, a lit building, a cluster
    of hot pixels. Taking turns between cells lets a local crowd in only a few at a time, while
    a frame's stars, spread over the sky, keep nearly their order of brightness. Two a turn
    rather than one keep a bright cluster's stars early enough: with one a turn (8 x 8 cells)
    the Pleiades photo took 296 ms to solve, against 16 ms before and 11 ms with two (6 x 6
    cells). astrometry.net orders an image's sources the same way (solve-field's
    ``--uniformize``; Lang et al. 2010, AJ 139, 1782).
    """
    column = np.clip((np.asarray(x) / width * cells).astype(np.int64), 0, cells - 1)
    row = np.clip((np.asarray(y) / height * cells).astype(np.int64), 0, cells - 1)
    cell = row * cells + column
    by_cell = np.argsort(cell, kind="stable")
    first = np.searchsorted(cell[by_cell], cell[by_cell])  # where each spot's cell starts in by_cell
    rounds = np.empty(cell.size, dtype=np.int64)
    rounds[by_cell] = np.arange(cell.size) - first
    return rounds // per_turn


def solve_image(image: str | os.PathLike | NDArray | Image, *, fov_deg: float | None = None,
                fov_range_deg: tuple[float, float] | None = None, camera: Camera | None = None,
                epoch: Time | float | None = None, channel: str | int | None = None,
                detector=None, method: MethodName = "quads", options: MatcherOptionsBase | None = None,
                pixel_aspect: float | tuple[float, float] | None = None,
                parity: Parity | None = None, guided: bool = False) -> AttitudeSolution:
    """Lost-in-space attitude of an image: read, detect, solve.

    Parameters
    ----------
    image : path, ndarray or startrack.io.Image
        A FITS, PNG, JPEG or TIFF file, or a 2-D (or colour) array in counts.
    fov_deg, fov_range_deg, camera, method, options, pixel_aspect
        As in :func:`solve_stars`. When none of the first three is given and the image's header
        states a field the default search does not reach (an ultra-wide lens's EXIF focal length,
        a FITS WCS's scale, a telescope's ``FOCALLEN`` and ``XPIXSZ``; :mod:`startrack.identify._image_fov`),
        that field is searched first, then the default range; when it states none, the default
        range first, then (quads matcher, nothing matched) :data:`WIDE_RETRY_FOV_RANGE_DEG`.
    epoch : astropy.time.Time or float, optional
        Catalog epoch; default: the time the image's header states (FITS ``CATEPOCH``,
        ``DATE-OBS``, ``MJD-OBS``, EXIF ``DateTimeOriginal``; :mod:`startrack.identify._image_epoch`),
        else J2000.0.
    channel : str or int, optional
        Colour channel to use: 'r', 'g' or 'b' (default: R + G + B; see :mod:`startrack.io._channels`).
    detector : startrack.detect.StarDetector, optional
        Detection settings (default: :func:`startrack.detect.detect`'s).
    parity : {"normal", "mirrored", "either"}, optional
        As in :func:`solve_stars`, but the default is "either" (a photo may be a mirror image:
        a star diagonal, a flipped file), or the camera's when one is given, or "normal" with a
        method other than "quads". The streak solve of a smeared frame takes the image as given.
    guided : bool
        Once solved, also measure the catalog stars the solution predicts where the detector found
        none, accept those that stand above the image's own sky (0.1 wrong acceptances expected
        per image), and refit the attitude on all matched stars (:mod:`startrack.identify._guided`;
        ``guided_stars`` says how many were added). Not for a frame solved from its streaks.

    Returns
    -------
    AttitudeSolution
        With ``detections`` (the stars found, brightest first, then the ``guided_stars`` measured
        where the solution predicts them; ``matches.det_index`` indexes them). A smeared frame
        (its brightest spots elongated, :mod:`startrack._smeared_image`'s
        ``SMEARED_ELONGATION``; or a failed point solve of somewhat elongated spots) is solved from
        its streaks without being asked: the result is then a
        :class:`startrack.rate._streak_solve.StreakSolution` (``mode`` "streak", the attitude at
        mid-exposure ``t_mid_s`` after the exposure start, the rate when the header gives the
        exposure; ``detections`` are then the fitted streaks' light centroids, one per row of
        ``streaks``, which ``matches.det_index`` indexes). The patterns are formed from
        the point sources first (spots the detector marks extended or elongated come last).
        A point solve that matches nothing, or finds too few stars, is tried once more on the
        spots found with the detector's clutter test off, when there are more of them (lit
        clouds), and on a smeared frame also with the elongation test off and weighted centroids
        (star trails; :func:`_second_detection`). ``solve_time_s`` covers detection and identification,
        not reading the file nor what a process does once (loading the pattern database and the
        compiled search).
    """
    from .detect import StarDetector
    from .io import Image, read_image

    if detector is not None and not isinstance(detector, StarDetector):
        raise InvalidInputError(f"detector must be a startrack.detect.StarDetector, got {type(detector).__name__}")
    if not isinstance(guided, bool | np.bool_):
        raise InvalidInputError(f"guided must be True or False, got {guided!r}")
    method = check_options(method, options)
    img = image if isinstance(image, Image) else read_image(image, channel=channel)
    when = resolve_epoch(epoch, img.header)
    height, width = img.data.shape[:2]
    if camera is not None and isinstance(camera, Camera) and (camera.width, camera.height) != (width, height):
        raise InvalidInputError(f"the camera is {camera.width} x {camera.height} px but the image is "
                                f"{width} x {height} px")
    detector = (detector or StarDetector()).for_image(img)  # a JPEG's noise floor (:mod:`.detect._compression`)
    t0 = time.perf_counter()
    found = detector.detect(img.data)
    detect_s = time.perf_counter() - t0
    from . import _smeared_image as smeared_image

    smeared = functools.partial(smeared_image.solve_smeared_image, img.data, img.header, camera=camera, fov_deg=fov_deg,
                                fov_range_deg=fov_range_deg, epoch=when.jyear, method=method, pixel_aspect=pixel_aspect)
    elongation = smeared_image.smear_elongation(found)
    if elongation >= smeared_image.SMEARED_ELONGATION and (streaked := smeared()).solved:
        return smeared_image.image_solution(streaked, found, detect_s, when.source)
    point_solve = functools.partial(
        _point_solve, searches=_fov_searches(img.header, width, height, fov_deg, fov_range_deg, camera, method),
        method=method, options=options, width=width, height=height, fov_deg=fov_deg, camera=camera, flux=None,
        epoch=when, pixel_aspect=pixel_aspect, parity=parity,
        default_parity="either" if method == "quads" else "normal")
    solution = point_solve(found)
    if not solution.solved and smeared_image.SOME_ELONGATION <= elongation < smeared_image.SMEARED_ELONGATION \
            and (streaked := smeared()).solved:
        return smeared_image.image_solution(streaked, found, detect_s, when.source)
    solution = replace(solution, solve_time_s=detect_s + solution.solve_time_s, detections=found)
    if solution.status in SECOND_DETECTION_STATUSES:
        solution = _second_detection(img.data, solution, detector, point_solve,
                                     trails=elongation >= smeared_image.SOME_ELONGATION)
    return _with_guided(img.data, solution, detector) if guided and solution.solved else solution


SECOND_DETECTION_STATUSES = (Status.NO_MATCH, Status.TOO_FEW_STARS)
"""A point solve that ends so is tried once more on a second detection (:func:`_second_detection`);
one out of time is not (it would take as long again)."""
SECOND_DETECTION_MIN_SPOTS = 3
"""Spots the clutter test must have refused for the second solve of a frame of round spots."""


def _second_detection(data: NDArray, failed: AttitudeSolution, detector,
                      point_solve: Callable[[Detections], AttitudeSolution], trails: bool = False) -> AttitudeSolution:
    """The image detected again with the clutter test off and solved (``point_solve``), when that
    finds at least :data:`SECOND_DETECTION_MIN_SPOTS` more spots; with ``trails`` (the brightest
    spots elongated: :data:`startrack._smeared_image.SOME_ELONGATION`), with the elongation test
    off too and the weighted centroid, and solved whatever the count. The ``failed`` solution
    when there is no second solve or it fails too. ``solve_time_s`` counts both.

    The clutter test refuses the spots of tiles whose background is busy (lit cloud, foliage, a
    roof; :mod:`startrack.detect._background`), and with them the stars of clear sky in a tile
    that a cloud's edge crosses. Under partial clouds (``benchmarks/photo_hazards.py``), that
    left 9-29 spots to four photos that did not solve, which solved right from the 12-34 spots
    found without the test. On a frame of star trails, the elongation test refuses the longest,
    and the windowed centroider, whose window is a star's size, settles on a piece of a trail
    rather than its middle: crappy.jpg with trails of 28 px solves so (``photo_transforms.py``'s
    trailed photos: 2 of 8 at 24 px, none before). A wrong match is no likelier than in any
    solve: the false-match probability limit is the same.
    """
    relaxed = {"max_clutter": None, **({"max_elongation": None, "centroid": "weighted"} if trails else {})}
    if all(getattr(detector, key) == value for key, value in relaxed.items()):  # nothing to relax
        return failed
    t0 = time.perf_counter()
    found = replace(detector, **relaxed).detect(data)
    detect_s = time.perf_counter() - t0
    if not trails and len(found) < len(require(failed.detections, "the failed solve's detections")) \
            + SECOND_DETECTION_MIN_SPOTS:
        return replace(failed, solve_time_s=failed.solve_time_s + detect_s)
    second = point_solve(found)
    spent = failed.solve_time_s + detect_s + second.solve_time_s
    if not second.solved:
        return replace(failed, solve_time_s=spent)
    return replace(second, solve_time_s=spent, detections=found)


WIDE_RETRY_FOV_RANGE_DEG = (90.0, MAX_FOV_DEG)
"""With nothing said about the field, an image whose stars match nothing in the default search
(no match, or none within the time limit) is searched again over these fields (deg; from 90,
overlapping the default's top): an ultra-wide lens's photo of 100-150 deg whose EXIF is gone (a
screenshot, an export, a web upload). It costs a search that fails: 0.5 s on a list of 40 random
spots (after the default's 0.8 s); about 1 s on an image of 40 random spots, whose default search
ran out of its 5 s (6.72 s in all, 5.67 s before)."""


def _given_fov_source(fov_deg: float | None, fov_range_deg: tuple[float, float] | None, camera: Camera | None) -> str:
    """:attr:`AttitudeSolution.fov_source` of a solve with these options: "camera", "given" or "default"."""
    if camera is not None:
        return "camera"
    return "default" if fov_deg is None and fov_range_deg is None else "given"


def _fov_searches(header: Mapping[str, Any], width: int, height: int, fov_deg: float | None,
                  fov_range_deg: tuple[float, float] | None, camera: Camera | None,
                  method: MethodName) -> list[tuple[tuple[float, float] | None, str]]:
    """The ``fov_range_deg`` of each point solve to try, in turn, with its
    :attr:`AttitudeSolution.fov_source`: the one given; when nothing is given about the field,
    first the range the image's header states if the default search does not reach it
    (:func:`.identify.stated_search_range`: an ultra-wide lens's EXIF, a telescope's FITS focal
    length), then the default search; when the header states none, the default search and then,
    for the quads matcher, :data:`WIDE_RETRY_FOV_RANGE_DEG`."""
    source = _given_fov_source(fov_deg, fov_range_deg, camera)
    if source != "default":
        return [(fov_range_deg, source)]
    stated = stated_search_range(header, width, height)
    if stated is not None:
        return [(stated, "header"), (None, "default")]
    return [(None, "default"), (WIDE_RETRY_FOV_RANGE_DEG, "wide")] if method == "quads" else [(None, "default")]


def _point_solve(found: Detections, searches: list[tuple[tuple[float, float] | None, str]], method: MethodName,
                 options: MatcherOptionsBase | None, **request_args) -> AttitudeSolution:
    """Solve the detected spots (:func:`search_order`) with :func:`build_request`'s ``request_args``
    and each (``fov_range_deg``, source) of ``searches`` in turn while the last found no match or
    ran out of time (the default search of an ultra-wide frame took 2.8 s on this machine, past
    the 5 s limit when it was busy); the result's ``solve_time_s`` counts every attempt. A failure
    after several is a timeout if one of them ran out of time (that range was not searched
    through), and its ``reason`` names the ranges (:func:`_searched_note`)."""
    order = search_order(found)
    spent, tried = 0.0, list[tuple[tuple[float, float], Status]]()
    for fov_range_deg, source in searches:
        request = build_request(found.x[order], found.y[order], fov_range_deg=fov_range_deg, **request_args)
        _check_parity_method(request, method)
        solution = _run(replace(request, rows=order[request.rows]), method, options, source)
        spent, tried = spent + solution.solve_time_s, [*tried, (request.fov_range_deg, solution.status)]
        if solution.status not in (Status.NO_MATCH, Status.TIMEOUT):
            break
    if len(tried) > 1 and not solution.solved:
        status = Status.TIMEOUT if any(s is Status.TIMEOUT for _, s in tried) else solution.status
        solution = replace(solution, status=status, reason=f"{solution.reason} ({_searched_note(tried)})")
    return replace(solution, solve_time_s=spent)


def _searched_note(tried: list[tuple[tuple[float, float], Status]]) -> str:
    """The note ``fields of view searched: 3-100 deg (out of time), then 90-150 deg`` for the
    (range, status) of each search tried."""
    ranges = (f"{lo:.3g}-{hi:.3g} deg" + (" (out of time)" if status is Status.TIMEOUT else "")
              for (lo, hi), status in tried)
    return "fields of view searched: " + ", then ".join(ranges)


def _with_guided(data: NDArray, solution: AttitudeSolution, detector) -> AttitudeSolution:
    """The solution refitted with the stars measured where it predicts them (:mod:`.identify._guided`),
    their time added to ``solve_time_s``."""
    from .identify import guided_stars, with_guided_stars

    t0 = time.perf_counter()
    refitted = with_guided_stars(solution, guided_stars(data, solution, detector=detector))
    return replace(refitted, solve_time_s=solution.solve_time_s + time.perf_counter() - t0)
