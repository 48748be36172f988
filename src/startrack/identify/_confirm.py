"""Confirmation of a candidate attitude against predicted catalog stars, shared by every
lost-in-space matcher (see :mod:`._verify` for the false-match probability).

The candidate is tested at the tight match radius. If it falls short, its matches at a loose
radius (``LOOSE_RADIUS_FACTOR`` times wider), when they are more than chance would give a wrong
candidate, are used to refit the attitude (and the focal length when it is free), and it is
tested again at the tight radius, counting only the stars the fit did not use beyond those it
had already matched (:meth:`Confirmer.confirm`): a pattern fitted
on a few close stars can be off by more than the tight radius at the far side of the image. For a lens that is
not calibrated the refit also takes the radial distortion k1 (and, when the pixel aspect is
searched, the aspect), and the loose pass is made twice: a wide lens bends the far side of the
image by tens of pixels, which a pinhole fit to a pattern near the centre cannot predict.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError, as_float_array
from ._candidate import Candidate
from ._refine import fit_pose, predicted_pairs, warm_up_pose
from ._verify import TEST_RADIUS_FRACTIONS, SkyBands, false_match_bound_counts, false_match_probability, field_cone

LOOSE_RADIUS_FACTOR = 2.5
"""First verification pass: match radius as a multiple of the final one."""

MIN_EXTRA_MATCHES = 2
"""A candidate needs at least this many stars beyond its pattern at the loose radius."""

MAX_LOOSE_CHANCE = 0.1
"""... and that many are refitted only when a wrong candidate would match at least as many at the
loose radius by chance with at most this probability (the binomial tail of :mod:`._verify`,
without the Bonferroni factor: the test only decides whether a refit is worth its cost, the
candidate still has to pass the tight test after it). On 100 lists of each condition of
``benchmarks/lis_benchmark.py`` (standard and ``--easy``, FOV 10, 15 and 20 deg, known or 5-35),
59 of the 73 candidates that reached a refit and were refused after it are turned away here; the
8 that the refit confirmed had chances of at most 0.013 (2 loose matches of 14, a pattern 0.8 deg
off)."""

LOOSE_ROUNDS_DISTORTED = 2
"""Loose passes for a lens whose distortion is fitted (one otherwise)."""

MIN_EXTRA_FOR_LENS = 6
"""The loose refit frees k1 and the pixel aspect only with at least this many stars beyond the
pattern: with fewer, the extra freedom pulls the loose matches of a wrong candidate in under
the tight radius, and the test at that radius would count them as evidence (one false match in
about 300 wide-field solves before this rule)."""


@dataclass(frozen=True)
class StarSet:
    """Catalog stars to confirm against: a KD-tree or a :class:`.verify.SkyBands` over their ICRS
    vectors (S, 3), their catalog rows (S,), and optionally a filter of the indices to use."""

    tree: cKDTree | SkyBands
    vectors: NDArray[np.float64]
    catalog_rows: NDArray[np.int64]
    keep: Callable[[NDArray], NDArray] | None = None


@dataclass(frozen=True)
class Confirmer:
    """The image side of confirmation: star positions (brightest first) and the test's settings.

    Attributes
    ----------
    x, y : ndarray, shape (N,)
    radius_px : float
        Tight match radius.
    verify_stars : int
        Brightest image stars tested.
    max_false_match_prob : float
    fit_focal : bool
        Refit the focal length with the attitude in the loose pass.
    fit_distortion : bool
        Also refit k1 there (a lens that is not calibrated), in up to
        :data:`LOOSE_ROUNDS_DISTORTED` passes.
    fit_aspect : bool
        Also refit the pixel aspect there (when it is searched).
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    radius_px: float
    verify_stars: int
    max_false_match_prob: float
    fit_focal: bool
    fit_distortion: bool = False
    fit_aspect: bool = False

    def __post_init__(self) -> None:
        warm_up_pose()  # the loose pass refits poses: compile (or load) that before a matcher's clock starts

    def confirm(self, stars: StarSet, rot: Rotation | NDArray, camera: Camera, pattern_img: NDArray,
                n_trials: int, pool_end: int = 0) -> Candidate | None:
        """A verified :class:`Candidate`, or None (see the module docstring). ``rot``: the candidate
        attitude (camera from ICRS), a Rotation, a unit scalar-last quaternion (4,) or a rotation
        matrix (3, 3); the candidate keeps it as a matrix.
        ``pool_end``: one past the faintest star rank the patterns are drawn from; the test covers
        :attr:`verify_stars` stars, more when the pool reaches deeper (half as many again beyond it).

        After a loose refit, the stars that only the loose radius had matched are fitted, not
        found: the test counts the stars the candidate matched at the tight radius before any
        refit and those the refit newly brings in, not the ones it pulled in (a refit with a free
        focal length can pull a wrong candidate's chance loose matches under the tight radius:
        one false match in about 300 wide-field solves before this rule)."""
        matrix = _attitude(rot)
        n = min(len(self.x), max(self.verify_stars, pool_end + self.verify_stars // 2))
        xs, ys = self.x[:n], self.y[:n]
        reach_px = LOOSE_RADIUS_FACTOR * self.radius_px
        field = _Field(stars, matrix, camera, xs, ys, reach_px)
        prob, tight = self._verify(field, pattern_img, n_trials, np.zeros(0, np.int64))
        fitted = np.zeros(0, np.int64)
        for _ in range(LOOSE_ROUNDS_DISTORTED if self.fit_distortion else 1):
            if prob <= self.max_false_match_prob:
                return field.candidate(tight, prob)
            img_i, cat_j, _ = field.matches(reach_px)
            extra = np.count_nonzero(_not_in(img_i, pattern_img))
            if not _worth_refit(field, int(extra), len(pattern_img), reach_px):
                return None
            fitted = np.union1d(fitted, img_i[_not_in(img_i, tight) & _not_in(img_i, pattern_img)])
            lens = bool(extra >= MIN_EXTRA_FOR_LENS)
            refit, camera, _ = fit_pose(field.matrix, field.camera, field.vectors[cat_j], xs[img_i], ys[img_i],
                                        fit_focal=self.fit_focal, fit_k1=self.fit_distortion and lens,
                                        fit_aspect=self.fit_aspect and lens)
            field = _Field(stars, refit, camera, xs, ys, reach_px)
            prob, tight = self._verify(field, pattern_img, n_trials, fitted)
        return field.candidate(tight, prob) if prob <= self.max_false_match_prob else None

    def _verify(self, field: _Field, pattern_img: NDArray, n_trials: int,
                fitted: NDArray) -> tuple[float, NDArray[np.int64]]:
        """The false-match bound of the tight-radius matches among the field's image stars other
        than the pattern's and the ``fitted`` ones, at each radius of
        :data:`.verify.TEST_RADIUS_FRACTIONS`; and the image stars matched at the tight radius
        (the field keeps their catalog stars)."""
        tight, field.tight_catalog, d2 = field.matches(self.radius_px)
        n_stars = len(field.xs)
        counted = np.ones(n_stars, dtype=bool)  # the stars the test counts: not the pattern's or fitted
        pattern_img = np.asarray(pattern_img, dtype=np.int64)
        counted[pattern_img[pattern_img < n_stars]] = False
        counted[fitted] = False
        counted_d2 = d2[counted[tight]]  # all within the tight radius: the matches at f r are those within f r
        counts = [int(np.count_nonzero(counted_d2 <= (f * self.radius_px) * (f * self.radius_px)))
                  for f in TEST_RADIUS_FRACTIONS]
        n_tested = n_stars - len(pattern_img) - len(fitted)
        if max(counts) == 0 or n_tested <= 0:
            return 1.0, tight
        prob = false_match_bound_counts(counts, n_tested, field.n_in_image, self.radius_px, field.camera.width,
                                        field.camera.height, n_trials)
        return prob, tight


class _Field:
    """The catalog stars that can land in the image of one attitude (matrix (3, 3), camera from
    ICRS) and camera: their indices into a :class:`StarSet` (cone of :func:`.verify.field_cone`) and
    their ICRS vectors (C, 3); matched to the image stars ``xs``, ``ys`` (N,) once, within
    ``reach_px``, by :func:`.refine.predicted_pairs` (which projects them and keeps those inside the
    image, as :func:`.verify.project_stars` with :func:`.verify.match_nearest`), the matches at a
    smaller radius taken from those (a closest-first greedy match at a smaller radius keeps
    exactly the pairs of the match at the larger one that lie within it)."""

    def __init__(self, stars: StarSet, matrix: NDArray, camera: Camera, xs: NDArray, ys: NDArray, reach_px: float):
        self.stars, self.matrix, self.camera, self.xs, self.ys = stars, matrix, camera, xs, ys
        self.index = field_cone(stars.tree, matrix, camera, stars.keep)
        self.vectors = np.take(stars.vectors, self.index, axis=0)  # fancy indexing of (S, 3) costs several times more
        self.tight_catalog = np.zeros(0, np.int64)
        self.reach_px = reach_px
        self._pairs: tuple | None = None

    @property
    def n_in_image(self) -> int:
        """How many of the field's catalog stars the attitude puts inside the image."""
        return self._within_reach()[3]

    def matches(self, radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        """(image index into ``xs``, index into :attr:`vectors`, squared distance (px^2)) of the
        closest-first pairs within ``radius_px`` (at most :attr:`reach_px`)."""
        img_i, cat_j, d2, _ = self._within_reach()
        if radius_px < self.reach_px:
            keep = d2 <= radius_px * radius_px
            return img_i[keep], cat_j[keep], d2[keep]
        return img_i, cat_j, d2

    def _within_reach(self) -> tuple:
        """The pairs within :attr:`reach_px` and the count of stars in the image, made on first use."""
        if self._pairs is None:
            if self.index.size == 0 or len(self.xs) == 0:
                empty = np.zeros(0, np.int64)
                self._pairs = (empty, empty, np.zeros(0), 0)
            else:
                self._pairs = predicted_pairs(self.vectors, self.matrix, self.camera, self.xs, self.ys, self.reach_px)
        return self._pairs

    def candidate(self, image_index: NDArray, prob: float) -> Candidate:
        """The verified candidate of these matches at the tight radius, with this field's attitude
        matrix and camera."""
        rows = self.stars.catalog_rows[self.index[self.tight_catalog]]
        return Candidate(self.matrix, self.camera, image_index, rows, prob)


def _attitude(rot: Rotation | NDArray) -> NDArray[np.float64]:
    """The rotation matrix (3, 3) of an attitude given as a Rotation, a unit scalar-last
    quaternion (4,) or a matrix (3, 3)."""
    if isinstance(rot, Rotation):
        return rot.as_matrix()
    values = as_float_array(rot, "rot")
    if values.shape == (3, 3):
        return values
    if values.shape != (4,):
        raise InvalidInputError(f"rot must be a Rotation, a quaternion (4,) or a rotation matrix (3, 3), "
                                f"got shape {values.shape}")
    x, y, z, w = values.tolist()
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _worth_refit(field: _Field, extra: int, n_pattern: int, reach_px: float) -> bool:
    """Whether ``extra`` loose matches (image stars beyond the pattern's ``n_pattern`` within
    ``reach_px`` of the ``field``'s predicted stars) are enough to refit on: at least
    :data:`MIN_EXTRA_MATCHES`, and more than chance would give a wrong candidate
    (:data:`MAX_LOOSE_CHANCE`)."""
    if extra < MIN_EXTRA_MATCHES:
        return False
    chance = false_match_probability(extra, len(field.xs) - n_pattern, field.n_in_image, reach_px,
                                     field.camera.width, field.camera.height, 1)
    return chance <= MAX_LOOSE_CHANCE


def _not_in(values: NDArray, few: NDArray) -> NDArray[np.bool_]:
    """Mask of ``values`` (K,) not among ``few`` (a pattern's handful of stars); cheaper than np.isin."""
    return np.all(values[:, None] != np.asarray(few)[None, :], axis=1)


def match_radius_px(camera: Camera, given: float | None) -> float:
    """The tight match radius: the one given, else 0.3 % of the larger image side, at least 2 px."""
    return given or max(2.0, 0.003 * max(camera.width, camera.height))
