"""Availability of a rig: over random body attitudes, how often at least one head, and the joint
solution, has enough stars, with the Sun, the Earth's limb and the Moon excluding heads.

Body attitudes are uniform over SO(3). At each, every head's catalog stars are counted inside its
image (:func:`startrack.analysis._availability.star_counts`' test: the real rectangle, through the
camera model), and a head is blinded (its count set to 0) when a bright body enters its exclusion
cone (:mod:`._exclusion`). Then:

- a head *has enough stars* with at least ``min_stars`` (4: a pattern and one more, what a
  lost-in-space matcher needs);
- the *joint* solution has enough when some head has enough (the others are then predicted
  through their mountings), or when one head has a triangle (3 stars) and all the unblinded heads
  together hold ``min_joint_stars`` (6: :mod:`._pattern` confirms a triangle with three stars
  elsewhere; with two the chance probability, about 1e-2 x 1e-3 per candidate, does not reach
  1e-6).

Stars behind the Earth are not removed: an Earth-limb exclusion wider than the half-diagonal
keeps the Earth out of the field anyway.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..analysis._availability import CHUNK, _count_chunk
from ..catalog import load_catalog
from ..errors import check_instance, checked_count, checked_number, checked_rng
from ..frames import random_rotations
from ..rig import CameraRig
from ._exclusion import BrightBodies, blinded_mask

PATTERN_STARS = 3
"""Stars of one head that form the joint pattern's triangle."""


@dataclass(frozen=True)
class RigAvailability:
    """Star counts per head over random body attitudes, and the summary (module docstring).

    Attributes
    ----------
    counts : dict of str to ndarray of int, shape (P,)
        Stars in each head's image at each attitude (0 when blinded).
    blinded : dict of str to ndarray of bool, shape (P,)
    max_mag : float
    min_stars, min_joint_stars : int
    """

    counts: dict[str, NDArray[np.int64]]
    blinded: dict[str, NDArray[np.bool_]]
    max_mag: float
    min_stars: int
    min_joint_stars: int

    @property
    def head_enough(self) -> dict[str, NDArray[np.bool_]]:
        return {name: c >= self.min_stars for name, c in self.counts.items()}

    @property
    def any_head(self) -> NDArray[np.bool_]:
        """Attitudes where at least one head has enough stars alone."""
        return np.logical_or.reduce(list(self.head_enough.values()))

    @property
    def joint(self) -> NDArray[np.bool_]:
        """Attitudes where the joint solution has enough stars."""
        counts = np.stack(list(self.counts.values()))
        pattern = (counts.max(axis=0) >= PATTERN_STARS) & (counts.sum(axis=0) >= self.min_joint_stars)
        return self.any_head | pattern

    def fraction(self, name: str) -> float:
        """Fraction of attitudes where head ``name`` has enough stars."""
        return float(np.mean(self.head_enough[name]))

    def summary(self) -> dict:
        """Plain numbers: fractions for any head, the joint solution, and per head."""
        return {"any_head": float(np.mean(self.any_head)), "joint": float(np.mean(self.joint)),
                "heads": {n: {"enough": self.fraction(n), "blinded": float(np.mean(self.blinded[n])),
                              "mean_stars": float(np.mean(self.counts[n]))} for n in self.counts}}


MAX_POINTINGS = 10**8
"""The most pointings of one availability run: it keeps a count and a flag per pointing and head
(9 bytes each), 0.9 GB a head at this number."""


def rig_availability(rig: CameraRig, max_mag: float, n_pointings: int, rng: np.random.Generator | int | None = None,
                     *, bodies: BrightBodies | None = None, min_stars: int = 4, min_joint_stars: int = 6,
                     progress: Callable[[int, int], None] | None = None) -> RigAvailability:
    """Count each head's stars over random body attitudes (module docstring).

    Parameters
    ----------
    rig : CameraRig
    max_mag : float
        Catalog limit (V).
    n_pointings : int
        Random body attitudes.
    rng : Generator, int or None
    bodies : BrightBodies, optional
        Sun, Earth and Moon directions; None: no exclusion.
    min_stars, min_joint_stars : int
    progress : callable(done, total), optional
    """
    check_instance(rig, CameraRig, "rig")
    if bodies is not None:
        check_instance(bodies, BrightBodies, "bodies")
    checked_count(n_pointings, "n_pointings", 1, MAX_POINTINGS)
    checked_count(min_stars, "min_stars", 1)
    checked_count(min_joint_stars, "min_joint_stars", PATTERN_STARS)
    max_mag = checked_number(max_mag, "max_mag (V)", low=-2.0, high=20.0)
    vectors = load_catalog().brighter_than(max_mag).vectors()
    tree = cKDTree(vectors)
    rng = checked_rng(rng)
    counts = {h.name: np.zeros(n_pointings, dtype=np.int64) for h in rig}
    blinded = {h.name: np.zeros(n_pointings, dtype=bool) for h in rig}
    for start in range(0, n_pointings, CHUNK):
        stop = min(start + CHUNK, n_pointings)
        body = random_rotations(stop - start, rng)
        for head in rig:
            rot = head.rot_cam_from_body * body
            reach = min(math.radians(head.camera.fov_diagonal_deg) / 2.0 * 1.02, math.pi / 2)
            found = _count_chunk(head.camera, vectors, tree, rot, reach)
            blind = np.zeros(stop - start, dtype=bool) if bodies is None else \
                blinded_mask(head, bodies, rot.as_matrix()[:, 2, :])
            counts[head.name][start:stop] = np.where(blind, 0, found)
            blinded[head.name][start:stop] = blind
        if progress is not None:
            progress(stop, n_pointings)
    return RigAvailability(counts, blinded, float(max_mag), int(min_stars), int(min_joint_stars))
