"""Confirmation of a candidate attitude against predicted catalog stars, shared by every
lost-in-space matcher (see :mod:`.verify` for the false-match probability).

The candidate is tested at the tight match radius. If it falls short, its matches at a loose
radius (``LOOSE_RADIUS_FACTOR`` times wider) are used to refit the attitude (and the focal length
when it is free), and it is tested again at the tight radius, counting only the stars the fit
did not use beyond those it had already matched (:meth:`Confirmer.confirm`): a pattern fitted
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
from .candidate import Candidate
from .refine import refine_pointing, warm_up_pose
from .verify import false_match_bound, match_nearest, project_stars

LOOSE_RADIUS_FACTOR = 2.5
"""First verification pass: match radius as a multiple of the final one."""

MIN_EXTRA_MATCHES = 2
"""A candidate needs at least this many stars beyond its pattern at the loose radius."""

LOOSE_ROUNDS_DISTORTED = 2
"""Loose passes for a lens whose distortion is fitted (one otherwise)."""

MIN_EXTRA_FOR_LENS = 6
"""The loose refit frees k1 and the pixel aspect only with at least this many stars beyond the
pattern: with fewer, the extra freedom pulls the loose matches of a wrong candidate in under
the tight radius, and the test at that radius would count them as evidence (one false match in
about 300 wide-field solves before this rule)."""


@dataclass(frozen=True)
class StarSet:
    """Catalog stars to confirm against: KD-tree over their ICRS vectors (S, 3), their catalog
    rows (S,), and optionally a filter of the indices to use."""

    tree: cKDTree
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

    def confirm(self, stars: StarSet, rot: Rotation, camera: Camera, pattern_img: NDArray,
                n_trials: int, pool_end: int = 0) -> Candidate | None:
        """A verified :class:`Candidate`, or None (see the module docstring). ``pool_end``: one past
        the faintest star rank the patterns are drawn from; the test covers
        :attr:`verify_stars` stars, more when the pool reaches deeper (half as many again beyond it).

        After a loose refit, the stars that only the loose radius had matched are fitted, not
        found: the test counts the stars the candidate matched at the tight radius before any
        refit and those the refit newly brings in, not the ones it pulled in (a refit with a free
        focal length can pull a wrong candidate's chance loose matches under the tight radius:
        one false match in about 300 wide-field solves before this rule)."""
        n = min(len(self.x), max(self.verify_stars, pool_end + self.verify_stars // 2))
        found, tight = self._verify(stars, rot, camera, pattern_img, n_trials, n, np.zeros(0, np.int64))
        fitted = np.zeros(0, np.int64)
        for _ in range(LOOSE_ROUNDS_DISTORTED if self.fit_distortion else 1):
            if found is not None:
                return found
            proj = project_stars(stars.tree, stars.vectors, rot, camera, stars.keep)
            img_i, cat_i = match_nearest(self.x[:n], self.y[:n], proj.x, proj.y,
                                         LOOSE_RADIUS_FACTOR * self.radius_px)
            extra = np.count_nonzero(_not_in(img_i, pattern_img))
            if extra < MIN_EXTRA_MATCHES:
                return None
            fitted = np.union1d(fitted, img_i[_not_in(img_i, tight) & _not_in(img_i, pattern_img)])
            lens = extra >= MIN_EXTRA_FOR_LENS
            rot, camera, _ = refine_pointing(rot, camera, stars.vectors[proj.star[cat_i]], self.x[img_i],
                                             self.y[img_i], fit_focal=self.fit_focal,
                                             fit_k1=self.fit_distortion and lens, fit_aspect=self.fit_aspect and lens)
            found, _ = self._verify(stars, rot, camera, pattern_img, n_trials, n, fitted)
        return found

    def _verify(self, stars: StarSet, rot, camera, pattern_img, n_trials: int, n: int,
                fitted: NDArray) -> tuple[Candidate | None, NDArray[np.int64]]:
        """The candidate if its tight-radius matches among the first ``n`` stars, other than the
        pattern's and the ``fitted`` ones, make a false match unlikely enough (else None); and
        the image stars matched at the tight radius."""
        proj = project_stars(stars.tree, stars.vectors, rot, camera, stars.keep)
        img_i, cat_i = match_nearest(self.x[:n], self.y[:n], proj.x, proj.y, self.radius_px)
        extra = _not_in(img_i, pattern_img) & _not_in(img_i, fitted)
        d2 = (self.x[img_i[extra]] - proj.x[cat_i[extra]]) ** 2 + (self.y[img_i[extra]] - proj.y[cat_i[extra]]) ** 2
        prob = false_match_bound(d2, n - len(pattern_img) - len(fitted), proj.star.size, self.radius_px,
                                 camera.width, camera.height, n_trials)
        if prob > self.max_false_match_prob:
            return None, img_i
        return Candidate(rot, camera, img_i, stars.catalog_rows[proj.star[cat_i]], prob), img_i


def _not_in(values: NDArray, few: NDArray) -> NDArray[np.bool_]:
    """Mask of ``values`` (K,) not among ``few`` (a pattern's handful of stars); cheaper than np.isin."""
    return np.all(values[:, None] != np.asarray(few)[None, :], axis=1)


def match_radius_px(camera: Camera, given: float | None) -> float:
    """The tight match radius: the one given, else 0.3 % of the larger image side, at least 2 px."""
    return given or max(2.0, 0.003 * max(camera.width, camera.height))
