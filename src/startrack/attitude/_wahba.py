"""Wahba's problem: shared pieces of every solver and the ``solve_wahba`` dispatcher.

Wahba's problem (Huffman 2006 §6.1.1 eq. 6.8): find the rotation R minimising

    L(R) = 1/2 sum_i w_i |b_i - R r_i|^2

for observed (camera / body frame) unit vectors b_i and reference (e.g. ICRS catalog) unit
vectors r_i. R is returned as a ``scipy.spatial.transform.Rotation`` that maps reference vectors
onto observed ones, ``R.apply(r_i) ~ b_i``; with ICRS references it is ``rot_cam_from_icrs``.

Quaternion convention (Huffman 2006 Appendix A): scipy's scalar-last, active (Hamilton) quaternions
``q = (x, y, z, w)``. Shuster's Davenport matrix pairs with the *passive* attitude matrix
A(q) = R(q)^T; written for the active convention the only change is the sign of z, which here is
``z = sum_i w_i (r_i x b_i)`` (Shuster's is ``sum_i w_i (b_i x r_i)``). With that z the top
eigenvector of K is directly the scipy quaternion of R (the tests check ``R.apply(r) ~ b``).

Every solver (one module each) provides a *core*: a function of batched, normalised inputs
``(observed (M, N, 3), reference (M, N, 3), weights (M, N) summing to 1)`` returning scalar-last
quaternions (M, 4). Each module's public solver is a plain function with the same signature and
result, which runs its core through :func:`solve_with`: the input checks, the degeneracy test,
the loss and the covariance. A solver whose error statistics differ from the optimum's (TRIAD)
or that has its own closed form (SVD, FOAM) also passes a *covariance core* ``(observed,
reference, weights, sigma_rad) -> (M, 3, 3)``; the default is the QUEST covariance, which is that
of every solver reaching the Wahba optimum.

Why :class:`WahbaResult` and not :class:`startrack.results.AttitudeSolution`: a solver works on
a batch of M problems at once and knows nothing of images, so its result holds stacked arrays
(rotation, loss, covariance, status); ``AttitudeSolution`` is the per-image result (RA, Dec,
roll, camera, matches, residuals) that the solve pipeline builds from one of these.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, check_choice
from ..results import Status
from ._covariance import covariance_batch
from ._inputs import as_per_vector, as_vector_pair, degenerate_mask, normalised_weights

Vectors = NDArray[np.float64]
SolverCore = Callable[[Vectors, Vectors, NDArray[np.float64]], NDArray[np.float64]]
CovarianceCore = Callable[[Vectors, Vectors, NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]

DEGENERATE_REASON = (
    "fewer than two non-parallel vectors with non-zero weight: the rotation about their common "
    "direction is undetermined"
)

WahbaMethod = Literal["quest", "qmethod", "svd", "foam", "esoq2", "olae", "pad", "triad"]
"""The solvers :func:`solve_wahba` selects by name (one module each)."""

METHODS: tuple[WahbaMethod, ...] = get_args(WahbaMethod)
"""Names accepted by :func:`solve_wahba`'s ``method``, in :data:`WahbaMethod`'s order."""

_MODULES = {
    "quest": ("quest", "quest"),
    "qmethod": ("qmethod", "q_method"),
    "svd": ("svd", "svd_method"),
    "foam": ("foam", "foam"),
    "esoq2": ("esoq2", "esoq2"),
    "olae": ("olae", "olae"),
    "pad": ("pad", "pad"),
    "triad": ("triad", "triad"),
}


@dataclass(frozen=True)
class WahbaResult:
    """Solution of one Wahba problem, or of a batch of M problems.

    Attributes
    ----------
    rotation : Rotation or None
        Maps reference vectors onto observed ones (``rot_cam_from_icrs`` for ICRS references and
        camera observations). Stacked (length M) for a batch, with the identity in the slots of
        degenerate problems; None for a single degenerate problem.
    loss : float or ndarray, shape (M,)
        Wahba loss ``1/2 sum_i w_i |b_i - R r_i|^2`` with the caller's weights (with weights from
        ``sigma_rad`` it is half the chi-square of the fit). NaN when degenerate.
    covariance_rad2 : ndarray, shape (3, 3) or (M, 3, 3), or None
        Covariance of the small-angle attitude error in the camera (observed) frame, rad^2
        (:func:`startrack.attitude._covariance.attitude_covariance`). None when no ``sigma_rad``
        was given; NaN (or None for a single problem) when degenerate.
    status : Status or ndarray of Status, shape (M,)
        ``Status.OK``, or ``Status.DEGENERATE`` when fewer than two non-parallel vectors.
    reason : str or ndarray of str, shape (M,)
        Why the status is not OK; empty when it is.
    """

    rotation: Rotation | None
    loss: float | NDArray[np.float64]
    covariance_rad2: NDArray[np.float64] | None
    status: Status | NDArray[np.object_]
    reason: str | NDArray[np.object_]

    @property
    def ok(self) -> bool | NDArray[np.bool_]:
        """True where the problem was solved (a bool, or a bool array (M,) for a batch)."""
        if isinstance(self.status, Status):
            return self.status is Status.OK
        return np.array([s is Status.OK for s in self.status], dtype=bool)


def attitude_profile_matrix(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Attitude profile matrix ``B = sum_i w_i b_i r_i^T``, shape (..., 3, 3).

    Inputs are ``observed`` and ``reference`` (..., N, 3) and ``weights`` (..., N) (Huffman 2006
    §6.1.4 eq. 6.38). Wahba's problem is equivalent to maximising ``tr(R B^T)``.
    """
    return np.swapaxes(observed * weights[..., None], -1, -2) @ reference


_Z_ROWS, _Z_COLS = np.array([2, 0, 1]), np.array([1, 2, 0])
_DIAGONAL = np.arange(3)


def davenport_parts(
    profile: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``sigma = tr B`` (...,), ``S = B + B^T`` (..., 3, 3) and z (..., 3) of a profile matrix.

    z is the active-convention vector ``sum_i w_i (r_i x b_i)``, i.e.
    ``(B32 - B23, B13 - B31, B21 - B12)`` (see the module docstring for the sign).
    """
    sigma = profile[..., 0, 0] + profile[..., 1, 1] + profile[..., 2, 2]
    s = profile + np.swapaxes(profile, -1, -2)
    antisymmetric = profile - np.swapaxes(profile, -1, -2)
    z = antisymmetric[..., _Z_ROWS, _Z_COLS]  # (B32 - B23, B13 - B31, B21 - B12)
    return sigma, s, z


def davenport_matrix(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """Davenport's symmetric K (..., 4, 4), scalar last, from B (..., 3, 3).

    ``K = [[S - sigma I, z], [z^T, sigma]]`` (Huffman 2006 §6.1.3) with the
    active-convention z of :func:`davenport_parts`. ``q^T K q = tr(R(q) B^T)`` for a unit
    scipy quaternion q, so the eigenvector of the largest eigenvalue is the optimal attitude and
    that eigenvalue is ``sum(w) - loss``.
    """
    sigma, s, z = davenport_parts(profile)
    k = np.empty(profile.shape[:-2] + (4, 4))
    k[..., :3, :3] = s
    k[..., _DIAGONAL, _DIAGONAL] -= sigma[..., None]
    k[..., :3, 3] = z
    k[..., 3, :3] = z
    k[..., 3, 3] = sigma
    return k


def weights_from_sigma(sigma_rad: ArrayLike) -> NDArray[np.float64]:
    """Inverse-variance weights ``1 / sigma_i^2`` (rad^-2) from per-vector 1-sigma errors (rad).

    The seed's normalised weights ``a_i = sigma_tot^2 / sigma_i^2`` (Huffman 2006 §6.1.3) differ only by a
    common factor, which does not change the solution; these keep the loss equal to half the
    chi-square.
    """
    sigma = np.asarray(sigma_rad, dtype=float)
    if not np.all(np.isfinite(sigma) & (sigma > 0.0)):
        raise InvalidInputError("sigma_rad must be finite and positive (1-sigma angle in radians)")
    return 1.0 / sigma**2


def wahba_loss(
    matrices: NDArray[np.float64],
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    weights: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Wahba loss (M,) of rotation matrices (M, 3, 3) on problems (M, N, 3) with weights (M, N).

    Computed from the residual vectors, not as ``sum(w) - lambda_max``, so it keeps its precision
    for nearly noise-free data.
    """
    residual = observed - np.einsum("mij,mnj->mni", matrices, reference)
    return 0.5 * np.einsum("mn,mni,mni->m", weights, residual, residual)


MIN_SIGMA_RAD = 1e-150
"""The smallest 1-sigma direction error accepted (rad): 1 / sigma^2 of a smaller one overflows float64."""


def _checked_inputs(observed, reference, weights, sigma_rad):
    """Batched unit vectors (M, N, 3), raw weights (M, N), sigma (M, N) or None, and batched."""
    obs, ref, batched = as_vector_pair(observed, reference)
    shape = obs.shape[:2]
    sigma = None
    if sigma_rad is not None:
        sigma = as_per_vector("sigma_rad", sigma_rad, shape, allow_zero=False)
        if np.any(sigma < MIN_SIGMA_RAD):
            raise InvalidInputError(f"sigma_rad must be at least {MIN_SIGMA_RAD:g} rad: the weights 1 / sigma^2 of "
                                    f"smaller ones overflow, got {float(sigma.min()):g}")
    if weights is not None:
        w = as_per_vector("weights", weights, shape, allow_zero=True)
    elif sigma is not None:
        w = weights_from_sigma(sigma)
    else:
        w = np.ones(shape)
    return obs, ref, w, sigma, batched


def _solve_ok(core: SolverCore, obs, ref, w, ok) -> NDArray[np.float64]:
    """Quaternions (M, 4) from ``core`` on the solvable problems; identity elsewhere."""
    quat = np.zeros(obs.shape[:1] + (4,))
    quat[:, 3] = 1.0
    if np.any(ok):
        quat[ok] = core(obs[ok], ref[ok], normalised_weights(w[ok]))
    return quat


def quest_covariance_core(
    observed: Vectors, reference: Vectors, weights: NDArray[np.float64], sigma_rad: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The default covariance core: the QUEST covariance of the observed vectors (Huffman 2006 eq. 6.36)."""
    return covariance_batch(observed, sigma_rad)


def sigma_weighted_profile(observed: Vectors, reference: Vectors, sigma_rad: NDArray[np.float64]
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``sigma_tot^2`` (M,) and the attitude profile matrix B (M, 3, 3) with weights 1 / sigma^2
    (normalised), the two pieces every closed-form covariance starts from (Huffman 2006 §6.1.4)."""
    inv_var = 1.0 / sigma_rad**2
    profile = attitude_profile_matrix(observed, reference, normalised_weights(inv_var))
    return 1.0 / inv_var.sum(axis=-1), profile


def solve_with(
    core: SolverCore,
    observed: ArrayLike,
    reference: ArrayLike,
    weights: ArrayLike | None = None,
    *,
    sigma_rad: ArrayLike | None = None,
    covariance: CovarianceCore = quest_covariance_core,
) -> WahbaResult:
    """Check the inputs, run a solver core on the solvable problems and assemble the result.

    Arguments are those of :func:`solve_wahba` (without ``method``); ``covariance`` computes the
    covariance from the solvable problems (batched unit vectors, normalised weights and sigmas).
    Degenerate problems are not passed to the cores; they get status DEGENERATE.
    """
    obs, ref, w, sigma, batched = _checked_inputs(observed, reference, weights, sigma_rad)
    ok = ~degenerate_mask(obs, ref, w)
    rotation = Rotation.from_quat(_solve_ok(core, obs, ref, w, ok))
    loss = np.where(ok, wahba_loss(rotation.as_matrix(), obs, ref, w), np.nan)
    cov = None
    if sigma is not None:
        cov = np.full(obs.shape[:1] + (3, 3), np.nan)
        if np.any(ok):
            cov[ok] = covariance(obs[ok], ref[ok], normalised_weights(w[ok]), sigma[ok])
    status = np.array([Status.OK if k else Status.DEGENERATE for k in ok], dtype=object)
    reason = np.array(["" if k else DEGENERATE_REASON for k in ok], dtype=object)
    if batched:
        return WahbaResult(rotation, loss, cov, status, reason)
    if not ok[0]:
        return WahbaResult(None, float("nan"), None, status[0], reason[0])
    cov0 = None if cov is None else cov[0]
    return WahbaResult(rotation[0], float(loss[0]), cov0, status[0], reason[0])


def solve_wahba(
    observed: ArrayLike,
    reference: ArrayLike,
    weights: ArrayLike | None = None,
    *,
    method: WahbaMethod = "quest",
    sigma_rad: ArrayLike | None = None,
) -> WahbaResult:
    """Best rotation mapping reference unit vectors onto observed ones (Wahba's problem).

    Parameters
    ----------
    observed : array_like, shape (N, 3) or (M, N, 3)
        Measured directions in the camera (body) frame; normalised here.
    reference : array_like, same shape as ``observed``
        The matching reference directions (e.g. ICRS catalog vectors); normalised here.
    weights : array_like, shape (N,) or (M, N), optional
        Non-negative weights; default ``1 / sigma_rad^2`` when ``sigma_rad`` is given, else 1.
        Only their ratios matter for the rotation.
    method : {"quest", "qmethod", "svd", "foam", "esoq2", "olae", "pad", "triad"}
        Shuster's QUEST with sequential rotations (:mod:`._quest`), Davenport's q-method
        (:mod:`._qmethod`), Markley's SVD (:mod:`._svd`), FOAM (:mod:`._foam`), Mortari's ESOQ2
        (:mod:`._esoq2`), OLAE (:mod:`._olae`), Crassidis-Markley predictive attitude
        determination (:mod:`._pad`) or TRIAD (:mod:`._triad`, two vectors of the set; not the
        optimum for more). All but TRIAD return the Wahba optimum.
    sigma_rad : float or array_like, shape (N,) or (M, N), optional
        1-sigma angular error of each observed vector (radians, per axis perpendicular to the
        vector). When given, the result carries the solver's covariance (camera frame, rad^2):
        the QUEST measurement model, which assumes weights proportional to ``1 / sigma_rad^2``
        (its SVD and FOAM closed forms for those methods, Shuster and Oh's for TRIAD).

    Returns
    -------
    WahbaResult
        ``rotation.apply(reference) ~ observed``; status DEGENERATE (not an exception) when fewer
        than two non-parallel vectors. Batched inputs give batched fields, solved without a
        Python loop over M.

    Raises
    ------
    InvalidInputError
        Bad shapes, non-finite or zero vectors, negative weights, non-positive sigmas, or an
        unknown ``method``.
    """
    return _solver(method)(observed, reference, weights, sigma_rad=sigma_rad)


def _solver(method: str) -> Callable[..., WahbaResult]:
    """The public solver function named ``method``."""
    module_name, function = _MODULES[check_choice(method, METHODS, "method")]
    module = importlib.import_module(f"{__package__}._{module_name}")  # deferred: they import us
    return getattr(module, function)
