"""Star overlay: identification from a prior attitude (Fowler 2013, Ch. 6
and §4 item 6).

In the thesis a user drags and rotates the catalog stars, projected with an initial attitude, over
the detected spots until they sit on them; every star-spot pair within the "feature deviation"
then becomes a match and the spots left over are noise. The catalog is cropped around the
initial attitude ("attitude deviation") and limited in magnitude. Here the dragging is a search:

1. Direct overlay: the catalog stars projected with the prior attitude are confirmed on the
   detections (:class:`.confirm.Confirmer`, which refits on its loose-radius matches). This
   confirms a good attitude (Fowler 2013's use) and ends the search when the prior is close.
2. Vote: for rolls about the boresight spaced over the prior's uncertainty, every
   (detection, catalog star) pair votes for the shift of the pattern (gnomonic coordinates of the
   prior's camera frame, bins wide enough for the distortion of a shift that large); the best
   (roll, shift) cells become attitudes.
3. Each attitude is refined by matching nearest neighbours within a shrinking radius and refitting
   (:func:`.refine.refine_pointing`), then confirmed with the false-match probability of
   :mod:`._verify`, its Bonferroni factor being the number of cells searched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..catalog import query_cone
from ..errors import InvalidInputError
from ..results import Status
from ._candidate import MatchOutcome
from ._confirm import LOOSE_RADIUS_FACTOR, Confirmer, StarSet, match_radius_px
from ._field_stars import field_stars
from ._options_base import MatcherOptionsBase
from ._refine import refine_pointing
from ._verify import match_nearest, project_stars

MAX_PRIOR_SIGMA_DEG = 10.0
"""Beyond this the prior says little: use a lost-in-space matcher."""


@dataclass(frozen=True)
class OverlayOptions(MatcherOptionsBase):
    """Settings of the overlay matcher.

    Attributes
    ----------
    verify_stars, match_radius_px, max_false_match_prob
        As for :class:`.pyramid.PyramidOptions`.
    search_sigmas : float
        The attitude is searched within this many ``prior_sigma_deg`` of the prior, per axis.
    vote_bin_px : float or None
        Width of a shift bin; None: the larger of 4 match radii and the distortion of the largest
        shift searched.
    hypotheses : int
        Best (roll, shift) cells refined and confirmed.
    refine_rounds : int
        Match-and-refit rounds of each hypothesis.
    """

    search_sigmas: float = 3.0
    vote_bin_px: float | None = None
    hypotheses: int = 5
    refine_rounds: int = 4

    def __post_init__(self) -> None:
        if not self.search_sigmas > 0:
            raise InvalidInputError(f"search_sigmas must be positive, got {self.search_sigmas}")
        if self.hypotheses < 1 or self.refine_rounds < 1:
            raise InvalidInputError("hypotheses and refine_rounds must be at least 1")


@dataclass(frozen=True)
class _Search:
    """The search grid: half-width of the shift / roll search (radians), shift bin (radians),
    and the rolls tried."""

    span: float
    bin: float
    rolls: NDArray[np.float64]

    @property
    def n_cells(self) -> int:
        return int(self.rolls.size * math.ceil(2 * self.span / self.bin) ** 2)


def catalog_star_set(max_mag: float, epoch_jyear: float = 2000.0) -> StarSet:
    """Catalog stars with V <= ``max_mag`` at ``epoch_jyear``, brightest first, to overlay
    (Fowler 2013's "limit star magnitude")."""
    stars = field_stars(float(max_mag), float(epoch_jyear))
    return StarSet(stars.tree, stars.vectors, stars.rows)


def match_overlay(x: ArrayLike, y: ArrayLike, camera: Camera, stars: StarSet, prior_rot: Rotation, *,
                  prior_sigma_deg: float, options: OverlayOptions | None = None) -> MatchOutcome:
    """Identify image stars near a prior attitude by overlaying the catalog (Fowler 2013 Ch. 6).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (focal length and distortion known).
    stars : StarSet
        Catalog stars to overlay (e.g. :func:`catalog_star_set`), to about the image's depth.
    prior_rot : Rotation
        Prior ``rot_cam_from_icrs``.
    prior_sigma_deg : float
        1-sigma uncertainty of the prior per axis (pointing and roll), degrees, 0 to 10; the
        search covers ``options.search_sigmas`` times it.
    options : OverlayOptions, optional

    Returns
    -------
    MatchOutcome
        OK with the confirmed candidate; TOO_FEW_STARS (fewer than 3 stars) or NO_MATCH (the
        detections match no attitude within the prior's uncertainty).
    """
    options = options or OverlayOptions()
    sigma = _checked_sigma(prior_sigma_deg)
    x, y = np.asarray(x, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
    if x.size < 3:
        return MatchOutcome(Status.TOO_FEW_STARS, f"the overlay needs at least 3 stars, got {x.size}", None, 0)
    radius = match_radius_px(camera, options.match_radius_px)
    confirmer = Confirmer(x, y, radius, options.verify_stars, options.max_false_match_prob, fit_focal=False)
    none, n = np.zeros(0, dtype=np.int64), min(x.size, options.verify_stars)
    direct = _refined(prior_rot, stars, camera, x[:n], y[:n], LOOSE_RADIUS_FACTOR * radius, radius, 1)
    found = confirmer.confirm(stars, direct, camera, none, 1)
    if found is not None:
        return MatchOutcome(Status.OK, "", found, 1)
    search = _search_grid(camera, options.search_sigmas * sigma, radius, options.vote_bin_px)
    for rot in _hypotheses(camera.pixel_to_vector(x[:n], y[:n]), stars, prior_rot, camera, search, options):
        rot = _refined(rot, stars, camera, x[:n], y[:n], 1.5 * search.bin * camera.fx, radius, options.refine_rounds)
        found = confirmer.confirm(stars, rot, camera, none, 1 + search.n_cells)
        if found is not None:
            return MatchOutcome(Status.OK, "", found, 1 + search.n_cells)
    return MatchOutcome(Status.NO_MATCH, f"no attitude within {options.search_sigmas:g} x {prior_sigma_deg:g} deg of "
                        "the prior matched the stars", None, 1 + search.n_cells)


def _checked_sigma(prior_sigma_deg: float) -> float:
    sigma = float(prior_sigma_deg)
    if not (math.isfinite(sigma) and 0.0 <= sigma <= MAX_PRIOR_SIGMA_DEG):
        raise InvalidInputError(f"prior_sigma_deg must be 0 to {MAX_PRIOR_SIGMA_DEG:g} deg, got {prior_sigma_deg!r}")
    return math.radians(sigma)


def _search_grid(camera: Camera, span: float, radius_px: float, bin_px: float | None) -> _Search:
    """Shift bins and rolls: a shift of ``span`` moves stars at the field's edge by up to
    span * tan^2(half diagonal) more than at its centre, and one roll step moves them one bin."""
    tan_edge = math.tan(math.radians(camera.fov_diagonal_deg) / 2.0)
    width = (bin_px / camera.fx) if bin_px else max(4.0 * radius_px / camera.fx, span * tan_edge**2)
    step = width / tan_edge
    n_roll = int(math.ceil(span / step))
    return _Search(max(span, width), width, step * np.arange(-n_roll, n_roll + 1, dtype=np.float64))


def _gnomonic(v: NDArray) -> NDArray[np.float64]:
    """Tangent-plane coordinates (x/z, y/z), shape (N, 2)."""
    return v[:, :2] / v[:, 2:3]


def _crop(stars: StarSet, prior_rot: Rotation, camera: Camera, span: float) -> NDArray[np.float64]:
    """Catalog vectors in the prior's camera frame within the field plus ``span``, shape (M, 3)
    (Fowler 2013's "attitude deviation" crop)."""
    radius = min(math.radians(camera.fov_diagonal_deg) / 2.0 + span, 1.2)
    idx = np.asarray(query_cone(stars.tree, prior_rot.inv().apply([0.0, 0.0, 1.0]), radius), dtype=np.int64)
    if stars.keep is not None and idx.size:
        idx = idx[stars.keep(idx)]
    return prior_rot.apply(stars.vectors[np.sort(idx)]).reshape(-1, 3)


def _hypotheses(img_vec: NDArray, stars: StarSet, prior_rot: Rotation, camera: Camera, search: _Search,
                options: OverlayOptions) -> list[Rotation]:
    """The best-voted (roll, shift) attitudes, most votes first, at most ``options.hypotheses``."""
    img = _gnomonic(img_vec)
    cat_vec = _crop(stars, prior_rot, camera, search.span)
    if cat_vec.shape[0] == 0:
        return []
    peaks = [(*_vote(img, _gnomonic(Rotation.from_rotvec([0.0, 0.0, roll]).apply(cat_vec)), search), roll)
             for roll in search.rolls]
    peaks.sort(key=lambda p: -p[0])
    return [_shift_rotation(shift) * Rotation.from_rotvec([0.0, 0.0, roll]) * prior_rot
            for _, shift, roll in peaks[:options.hypotheses]]


def _vote(img: NDArray, cat: NDArray, search: _Search) -> tuple[int, NDArray]:
    """Votes and mean shift (image - catalog, gnomonic) of the best 2 x 2 block of shift bins."""
    shift = (img[:, None, :] - cat[None, :, :]).reshape(-1, 2)
    shift = shift[np.all(np.abs(shift) < search.span, axis=1)]
    n_bins = int(math.ceil(2 * search.span / search.bin))
    cell = np.floor((shift + search.span) / search.bin).astype(np.int64).clip(0, n_bins - 1)
    hist = np.zeros((n_bins + 1, n_bins + 1), dtype=np.int64)
    np.add.at(hist, (cell[:, 0], cell[:, 1]), 1)
    block = hist[:-1, :-1] + hist[1:, :-1] + hist[:-1, 1:] + hist[1:, 1:]
    i, j = np.unravel_index(int(np.argmax(block)), block.shape)
    inside = (cell[:, 0] >= i) & (cell[:, 0] <= i + 1) & (cell[:, 1] >= j) & (cell[:, 1] <= j + 1)
    return int(block[i, j]), (shift[inside].mean(axis=0) if np.any(inside) else np.zeros(2))


def _shift_rotation(shift: NDArray) -> Rotation:
    """The rotation of the camera frame that moves the boresight to gnomonic point ``shift``."""
    h = float(np.hypot(*shift))
    if h == 0.0:
        return Rotation.identity()
    return Rotation.from_rotvec(np.array([-shift[1], shift[0], 0.0]) / h * math.atan(h))


def _refined(rot: Rotation, stars: StarSet, camera: Camera, x: NDArray, y: NDArray, start_px: float,
             radius_px: float, rounds: int) -> Rotation:
    """Match nearest neighbours within a radius halving from ``start_px`` down to the confirmer's
    loose radius, refitting the attitude each round (the overlay's "drag and rotate")."""
    match_px = start_px
    for _ in range(rounds):
        proj = project_stars(stars.tree, stars.vectors, rot, camera, stars.keep)
        img_i, cat_i = match_nearest(x, y, proj.x, proj.y, match_px)
        if img_i.size < 3:
            break
        rot, _, _ = refine_pointing(rot, camera, stars.vectors[proj.star[cat_i]], x[img_i], y[img_i],
                                    fit_focal=False)
        match_px = max(match_px / 2.0, LOOSE_RADIUS_FACTOR * radius_px)
    return rot
