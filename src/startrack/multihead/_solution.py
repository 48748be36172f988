"""What :func:`startrack.solve_rig` returns, and its settings."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..frames import radec_roll_from_rotation
from ..results import AttitudeSolution, StarMatches, Status

IDENTIFIED_BY_HEAD = "single-head"
"""``RigSolution.mode``: one head was identified lost-in-space, the others through the mountings."""
IDENTIFIED_JOINTLY = "joint-pattern"
"""``RigSolution.mode``: a triangle in one head, confirmed by the stars of the others."""


@dataclass(frozen=True)
class RigOptions:
    """Settings of :func:`startrack.solve_rig`.

    Attributes
    ----------
    min_head_stars : int
        Fewest matched stars (at least 3) for a head's own solution to count (its
        AttitudeSolution is OK and its consistency with the others is tested).
    window_px : float
        Smallest search radius around each star predicted through a mounting (px).
    window_sigmas : float
        The search radius is at least this many times the predicted position's 1-sigma (the
        attitude's uncertainty carried into the head).
    match_px : float
        Match radius once the joint attitude is fitted (px).
    refine_rounds : int
        Predict-match-fit rounds of the joint solution.
    catalog_max_mag : float
        Faintest catalog star predicted (V).
    consistency_chi2 : float
        A head whose own attitude, carried through its mounting, differs from the joint one by more
        than this chi-square (3 degrees of freedom, with the head's own covariance) is left out of
        the joint fit and listed in ``RigSolution.inconsistent_heads``; 25 is p ~ 1e-5.
    min_sigma_px : float
        Floor of a head's measured centroid noise (px).
    pattern_stars : int
        Brightest stars of a head whose triangles the joint pattern search tries.
    pattern_sigma_px : float
        Centroid error (1-sigma, px) the triangle tolerances of the joint pattern allow.
    max_false_match_prob : float
        The joint pattern is accepted when the probability that the other heads' stars matched a
        wrong attitude by chance is below this.
    timeout_s : float
        Time limit of the joint pattern search (s).
    """

    min_head_stars: int = 3
    window_px: float = 8.0
    window_sigmas: float = 5.0
    match_px: float = 2.5
    refine_rounds: int = 3
    catalog_max_mag: float = 9.5
    consistency_chi2: float = 25.0
    min_sigma_px: float = 0.05
    pattern_stars: int = 8
    pattern_sigma_px: float = 0.5
    max_false_match_prob: float = 1e-6
    timeout_s: float = 5.0

    def __post_init__(self) -> None:
        if not (isinstance(self.min_head_stars, int) and self.min_head_stars >= 3):
            raise InvalidInputError(f"min_head_stars must be a whole number >= 3, got {self.min_head_stars!r}")
        for name in ("window_px", "window_sigmas", "match_px", "consistency_chi2", "min_sigma_px",
                     "pattern_sigma_px", "timeout_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be positive, got {value!r}")
        if self.refine_rounds < 1 or self.pattern_stars < 3:
            raise InvalidInputError("refine_rounds must be >= 1 and pattern_stars >= 3")
        if not 0.0 < self.max_false_match_prob < 1.0:
            raise InvalidInputError(f"max_false_match_prob must be in (0, 1), got {self.max_false_match_prob!r}")


@dataclass(frozen=True)
class RigSolution:
    """One body attitude from the stars of every head of a rig, or the reason there is none.

    Attributes
    ----------
    status : Status
        OK, or TOO_FEW_STARS / NO_MATCH with ``reason``.
    reason : str
    rot_body_from_icrs : Rotation or None
        Maps ICRS vectors into the body frame; a head's attitude is its mounting times this.
    covariance_rad2 : ndarray, shape (3, 3) or None
        Covariance of the small-angle attitude error in the body frame, rad^2 (QUEST model over all
        matched stars of all heads, each weighted by its head's measured centroid noise).
    heads : dict of str to AttitudeSolution
        Each head's own solution from its own matched stars only (camera frame), or a failed one.
    matches : dict of str to StarMatches
        The stars of each head used in the joint fit (``det_index`` indexes the head's star list,
        or the detections of its detector for a split field).
    consistency_deg : float
        Largest angle between a head's own solution, carried through its mounting, and the joint
        one (NaN when no head has a solution of its own).
    heads_used : tuple of str
        Heads whose stars are in the joint fit.
    inconsistent_heads : tuple of str
        Heads left out because their own solution disagrees with the joint one (a wrong or drifted
        mounting; see :attr:`RigOptions.consistency_chi2`).
    sigma_cross_arcsec, sigma_roll_arcsec : dict of str to float
        The joint covariance's 1-sigma across and about each head's boresight, arcsec.
    centroid_sigma_px : dict of str to float
        Each head's centroid noise as measured by its residuals (the prior when too few stars).
    residuals_arcsec : dict of str to ndarray
        Angle between each matched star and its catalog star after the joint fit.
    mode : str
        How the rig was identified: :data:`IDENTIFIED_BY_HEAD` (``seed_head`` named) or
        :data:`IDENTIFIED_JOINTLY`; empty when not solved.
    seed_head : str
        The head identified first.
    false_match_prob : float
    solve_time_s : float
    detections : dict of str to Detections
        For a solve from images: each detector's detections (``det_index`` indexes them).
    fields : dict of str to FieldClassification
        For a solve from images: the field classification of each split detector's spots.
    """

    status: Status
    reason: str = ""
    rot_body_from_icrs: Rotation | None = None
    covariance_rad2: NDArray[np.float64] | None = None
    heads: dict[str, AttitudeSolution] = field(default_factory=dict)
    matches: dict[str, StarMatches] = field(default_factory=dict)
    consistency_deg: float = float("nan")
    heads_used: tuple[str, ...] = ()
    inconsistent_heads: tuple[str, ...] = ()
    sigma_cross_arcsec: dict[str, float] = field(default_factory=dict)
    sigma_roll_arcsec: dict[str, float] = field(default_factory=dict)
    centroid_sigma_px: dict[str, float] = field(default_factory=dict)
    residuals_arcsec: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    mode: str = ""
    seed_head: str = ""
    false_match_prob: float = 1.0
    solve_time_s: float = 0.0
    detections: dict = field(default_factory=dict)
    fields: dict = field(default_factory=dict)

    @property
    def solved(self) -> bool:
        return self.status is Status.OK

    @property
    def n_matched(self) -> int:
        """Stars in the joint fit, all heads together."""
        return int(sum(len(self.matches[h]) for h in self.heads_used))

    @property
    def quaternion_xyzw(self) -> NDArray[np.float64] | None:
        """``rot_body_from_icrs`` as (qx, qy, qz, qw) with qw >= 0, for files and CLI output."""
        return None if self.rot_body_from_icrs is None else self.rot_body_from_icrs.as_quat(canonical=True)

    def radec_roll_deg(self) -> tuple[float, float, float]:
        """RA, Dec of the body +z axis and roll about it (the :mod:`startrack.frames` format), deg."""
        if self.rot_body_from_icrs is None:
            return (math.nan, math.nan, math.nan)
        ra, dec, roll = (math.degrees(float(a)) for a in radec_roll_from_rotation(self.rot_body_from_icrs))
        return ra, dec, roll
