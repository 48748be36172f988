"""One Wahba solution over the matched stars of every head, in the body frame (Samaan 2002 Eq. 4–5).

Each head's matched camera-frame unit vectors are carried into the body frame through its mounting
(``v_body = rot_cam_from_body.inv().apply(v_cam)``) and all of them go into one Wahba problem with
the catalog vectors, each weighted by ``1 / sigma^2``, sigma its head's measured centroid noise
over its focal length (Davenport's q-method, :func:`startrack.attitude.solve_wahba`). The QUEST
covariance of that fit is the body-frame covariance (Huffman 2006 §6.1.3 eq. 6.36); split about each
head's boresight it gives that head's cross-boresight and roll uncertainty. The wide baseline of
two heads makes the weak roll axis of one the strong cross-boresight axis of the other.

A head's *own* solution is the same fit over its stars alone (camera frame), an
:class:`~startrack.results.AttitudeSolution`; the angle between it (carried through the mounting)
and the joint one, and its chi-square with the head's covariance, measure how well the mounting
agrees with the rest of the rig.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude import covariance_batch, covariance_to_body, degenerate_mask, q_method_quaternions, roll_cross_boresight
from ..catalog import load_catalog
from ..errors import require
from ..frames import angle_between, radec_roll_from_rotation
from ..results import AttitudeSolution, StarMatches, Status
from ..rig import RigHead
from ..units import ARCSEC
from ._stars import HeadStars


@dataclass(frozen=True)
class HeadMatch:
    """Stars of one head matched to catalog stars: rows of ``stars`` (K,), catalog rows (K,) of
    :func:`startrack.catalog.load_catalog` and their ICRS unit vectors (K, 3)."""

    stars: HeadStars
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    ref_icrs: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.image_index.size)

    @property
    def name(self) -> str:
        return self.stars.name

    @property
    def observed_cam(self) -> NDArray[np.float64]:
        return self.stars.vectors[self.image_index]

    @property
    def observed_body(self) -> NDArray[np.float64]:
        return self.stars.head.rot_cam_from_body.inv().apply(self.observed_cam).reshape(-1, 3)

    def take(self, keep: NDArray) -> HeadMatch:
        return HeadMatch(self.stars, self.image_index[keep], self.catalog_rows[keep], self.ref_icrs[keep])

    @classmethod
    def empty(cls, stars: HeadStars) -> HeadMatch:
        none = np.zeros(0, dtype=np.int64)
        return cls(stars, none, none, np.zeros((0, 3)))


@dataclass(frozen=True)
class JointFit:
    """The joint attitude ``rot_body_from_icrs`` and its body-frame covariance (3, 3), rad^2."""

    rot_body_from_icrs: Rotation
    covariance_rad2: NDArray[np.float64]


def weighted_fit(observed: NDArray, reference: NDArray, sigma_rad: NDArray) -> tuple[Rotation, NDArray] | None:
    """Davenport's q-method with weights ``1 / sigma^2`` and the QUEST covariance (rad^2, frame of
    ``observed``), on unit vectors (K, 3) already checked; None when degenerate (fewer than two
    non-parallel vectors). The cores of :func:`startrack.attitude.solve_wahba` without its input
    checks, which cost more than the fit on the few dozen stars of a rig frame."""
    if len(observed) < 2 or degenerate_mask(observed[None], reference[None], np.ones((1, len(observed))))[0]:
        return None
    inv_var = 1.0 / sigma_rad**2
    quat = q_method_quaternions(observed[None], reference[None], (inv_var / inv_var.sum())[None])[0]
    return Rotation.from_quat(quat), covariance_batch(observed[None], sigma_rad[None])[0]


def fit_joint(matches: list[HeadMatch], sigma_px: dict[str, float]) -> JointFit | None:
    """Weighted Wahba fit of every matched star of ``matches`` in the body frame (module
    docstring); None when they do not fix an attitude (fewer than two non-parallel stars)."""
    used = [m for m in matches if len(m)]
    if sum(len(m) for m in used) < 2:
        return None
    observed = np.concatenate([m.observed_body for m in used])
    reference = np.concatenate([m.ref_icrs for m in used])
    sigma = np.concatenate([np.full(len(m), sigma_px[m.name] / m.stars.head.camera.fx) for m in used])
    found = weighted_fit(observed, reference, sigma)
    return None if found is None else JointFit(*found)


def residuals_px(match: HeadMatch, rot_cam_from_icrs: Rotation) -> NDArray[np.float64]:
    """Pixel offsets (K, 2) of the matched stars from where ``rot_cam_from_icrs`` puts their catalog stars."""
    px, py = match.stars.head.camera.vector_to_pixel(rot_cam_from_icrs.apply(match.ref_icrs).reshape(-1, 3))
    i = match.image_index
    return np.column_stack([match.stars.x[i] - px, match.stars.y[i] - py])


PRIOR_DOF = 4.0
"""Degrees of freedom the head's prior centroid noise counts for in :func:`measured_sigma_px`."""


def measured_sigma_px(match: HeadMatch, rot_cam_from_icrs: Rotation, floor_px: float) -> float:
    """A head's centroid noise per axis (px) measured by its residuals about ``rot_cam_from_icrs``.

    ``sigma^2 = (sum d^2 + PRIOR_DOF sigma_prior^2) / (2K - 3 + PRIOR_DOF)`` for K matched stars
    (two residual components each, three attitude parameters fitted): the residuals decide once
    there are many stars, the head's prior ``centroid_sigma_px`` keeps three or four stars from
    claiming a noise far below it by chance. At least ``floor_px``.
    """
    prior = match.stars.head.centroid_sigma_px
    k = len(match)
    if k < 2:
        return prior
    d = residuals_px(match, rot_cam_from_icrs)
    variance = (float(np.sum(d * d)) + PRIOR_DOF * prior**2) / (max(2 * k - 3, 0) + PRIOR_DOF)
    return max(math.sqrt(variance), floor_px)


def head_split_arcsec(covariance_body: NDArray, head: RigHead) -> tuple[float, float]:
    """(cross-boresight, roll) 1-sigma (arcsec) of a body-frame covariance about a head's boresight."""
    roll, cross = roll_cross_boresight(covariance_body, head.boresight_body)
    return float(cross) / ARCSEC, float(roll) / ARCSEC


def own_solution(match: HeadMatch, floor_px: float, min_stars: int, false_match_prob: float = 1.0,
                 solve_time_s: float = 0.0) -> AttitudeSolution:
    """The head's attitude (camera frame) from its own matched stars only, or why there is none.

    The covariance uses the head's centroid noise measured by its residuals about this fit
    (:func:`measured_sigma_px`, at least ``floor_px``), not about the joint one: a head whose
    mounting is off fits its own stars well and disagrees with the others by more than its
    covariance allows."""
    k = len(match)
    if k < max(3, min_stars):
        return AttitudeSolution(status=Status.TOO_FEW_STARS,
                                reason=f"head {match.name!r}: {k} star(s) matched, its own solution needs "
                                       f"{max(3, min_stars)}")
    camera = match.stars.head.camera
    found = weighted_fit(match.observed_cam, match.ref_icrs, np.full(k, 1.0 / camera.fx))
    if found is None:
        return AttitudeSolution(status=Status.DEGENERATE, reason=f"head {match.name!r}: its matched stars are "
                                "all in one direction")
    rot, covariance = found
    covariance = covariance * measured_sigma_px(match, rot, floor_px) ** 2  # computed for 1 px: scale
    ra, dec, roll = radec_roll_from_rotation(rot)
    matches = StarMatches(status=Status.OK, det_index=match.stars.index[match.image_index],
                          hip=load_catalog().hip[match.catalog_rows].astype(np.int64),
                          cat_vectors=match.ref_icrs, false_match_prob=false_match_prob)
    return AttitudeSolution(
        status=Status.OK, rot_cam_from_icrs=rot, covariance_rad2=covariance,
        ra_deg=math.degrees(ra), dec_deg=math.degrees(dec), roll_deg=math.degrees(roll), fov_deg=camera.fov_deg,
        camera=camera, matches=matches, false_match_prob=false_match_prob, solve_time_s=solve_time_s,
        residuals_arcsec=angle_between(rot.apply(match.ref_icrs).reshape(-1, 3), match.observed_cam) / ARCSEC)


def own_body(solution: AttitudeSolution, head: RigHead) -> tuple[Rotation, NDArray[np.float64]]:
    """A head's own attitude carried into the body frame, and its covariance in body axes."""
    rot = head.rot_cam_from_body.inv() * require(solution.rot_cam_from_icrs, "the head's attitude")
    return rot, covariance_to_body(require(solution.covariance_rad2, "the head's covariance"), head.rot_cam_from_body)


def disagreement(rot_a: Rotation, cov_a: NDArray, rot_b: Rotation, cov_b: NDArray) -> tuple[float, float]:
    """Angle (rad) between two body attitudes and its chi-square with covariance ``cov_a + cov_b``
    (``cov_b`` may be subtracted by the caller when b includes a, see :func:`chi2_against_joint`)."""
    d = (rot_a * rot_b.inv()).as_rotvec()
    return float(np.linalg.norm(d)), _chi2(d, cov_a + cov_b)


def chi2_against_joint(rot_own: Rotation, cov_own: NDArray, joint: JointFit, included: bool) -> float:
    """Chi-square of a head's own body attitude against the joint one: with covariance
    ``P_own - P_joint`` when the head is in the joint fit (the joint is then correlated with it),
    ``P_own + P_joint`` when it is not."""
    d = (rot_own * joint.rot_body_from_icrs.inv()).as_rotvec()
    cov = cov_own - joint.covariance_rad2 if included else cov_own + joint.covariance_rad2
    return _chi2(d, cov)


def _chi2(d: NDArray, cov: NDArray) -> float:
    """``d^T cov^-1 d`` with the covariance's eigenvalues floored at 1e-6 of the largest."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    floor = max(float(values.max()), 1e-30) * 1e-6
    proj = vectors.T @ d
    return float(np.sum(proj * proj / np.maximum(values, floor)))
