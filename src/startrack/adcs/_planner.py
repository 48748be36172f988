"""Minimum-energy slew planning by virtual motion camouflage on an LGL grid (Sease 2013 ch. 5,
eq. 5.1-5.15 and 5.35-5.38; Sease 2013 Chapter 5).

Minimise the coil energy ``1/2 int I^2 R dt`` of a single-axis slew from (q2, w) at t0 to
(q2, w) at t0 + tf, with ``I = J22 w' / (n A |B| (1 - 2 q2^2))`` (eq. 5.6), under
``|I| <= I_max`` and ``|q2| <= 1`` at the nodes. Discretised on N LGL nodes (:mod:`._lgl`), the
cost is ``1/2 R (tf / 2) sum_i w_i I_i^2``.

Virtual motion camouflage (eq. 5.10): the path is ``q2_i = q_r + nu_i (q_p,i - q_r)`` with a
cubic prey path q_p that meets the four boundary values (eq. 5.35-5.38) and a reference point
q_r = 2 beyond the reachable range. ``nu_1 = nu_N = 1`` put the ends on the prey's; the two end
rates fix ``nu_2`` and ``nu_{N-1}`` by a 2 x 2 linear solve (eq. 5.11-5.12), so N - 4 path-control
parameters remain, found by scipy's SLSQP (in place of the seed's NLopt / fmincon). Rates follow
from eq. 5.9, ``w = 2 q2' / sqrt(1 - q2^2)`` (the seed's eq. 5.13 prints the root's argument
wrongly), and ``w' = D w`` with the differentiation matrix scaled by 2 / tf.

Between nodes the path is eq. 5.10 in continuous time: nu(t) is the degree N - 1 polynomial
through the PCPs (the one D differentiates exactly) and q_p(t) the cubic, so
``q2' = nu' (q_p - q_r) + nu q_p'`` holds everywhere and the end rates are met exactly
(:meth:`PlannedPath.sample`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.polynomial import legendre
from numpy.typing import NDArray
from scipy.optimize import minimize

from ..errors import InvalidInputError
from ._cubesat import CubeSat
from ._lgl import MIN_NODES, LGLGrid, lgl_grid, time_nodes

BOUND_SLACK = 1e-6
"""Relative slack on the current bound when judging a plan feasible."""


class PlanStatus(Enum):
    OK = "ok"
    INFEASIBLE = "infeasible"
    NOT_CONVERGED = "not converged"


@dataclass(frozen=True)
class PlannerOptions:
    """Settings of the planner.

    Attributes
    ----------
    n_nodes : int
        LGL nodes (the seed used 10), >= 4.
    q_ref : float
        VMC reference point q_r (seed: 2), outside [-1, 1].
    max_iter : int
        SLSQP iterations.
    ftol : float
        SLSQP tolerance on the cost (J).
    """

    n_nodes: int = 10
    q_ref: float = 2.0
    max_iter: int = 100
    ftol: float = 1e-14

    def __post_init__(self) -> None:
        if not (isinstance(self.n_nodes, int | np.integer) and self.n_nodes >= MIN_NODES):
            raise InvalidInputError(f"n_nodes must be a whole number >= {MIN_NODES}, got {self.n_nodes!r}")
        if not (math.isfinite(self.q_ref) and abs(self.q_ref) > 1):
            raise InvalidInputError(f"q_ref must lie outside [-1, 1] (the seed uses 2), got {self.q_ref!r}")


@dataclass(frozen=True)
class Boundary:
    """A boundary state: ``q2`` (= sin(theta / 2)) and the rate about y, rad/s."""

    q2: float
    omega_rad_s: float = 0.0

    @property
    def q2_dot(self) -> float:
        """dq2/dt = w / 2 sqrt(1 - q2^2) (eq. 5.9), 1/s."""
        return 0.5 * self.omega_rad_s * math.sqrt(max(0.0, 1.0 - self.q2 * self.q2))

    @classmethod
    def from_angle(cls, theta_rad: float, omega_rad_s: float = 0.0) -> Boundary:
        return cls(math.sin(0.5 * theta_rad), omega_rad_s)


@dataclass(frozen=True)
class PlannedPath:
    """A planned slew; after its end it holds the final angle (at the final rate).

    Attributes
    ----------
    status : PlanStatus
    reason : str
        Why the plan is not OK ('' when it is).
    t0_s, tf_s : float
        Start time and duration, s.
    times_s, q2, omega_rad_s, current_a : ndarray, shape (N,)
        Node times, attitude, rate about y and the coil current the path needs.
    nu : ndarray, shape (N,)
        Path-control parameters.
    cost_j : float
        The seed's cost ``1/2 int I^2 R dt`` (eq. 5.1) by the LGL quadrature, J: half the
        electrical energy the coil dissipates along the path.
    prey : ndarray, shape (4,)
        Cubic prey coefficients in time from ``t0_s`` (eq. 5.35).
    q_ref : float
        VMC reference point.
    """

    status: PlanStatus
    reason: str
    t0_s: float
    tf_s: float
    times_s: NDArray[np.float64]
    q2: NDArray[np.float64]
    omega_rad_s: NDArray[np.float64]
    current_a: NDArray[np.float64]
    nu: NDArray[np.float64]
    cost_j: float
    prey: NDArray[np.float64]
    q_ref: float

    @property
    def feasible(self) -> bool:
        return self.status is not PlanStatus.INFEASIBLE

    @property
    def t_end_s(self) -> float:
        return self.t0_s + self.tf_s

    def sample(self, t_s: float) -> tuple[float, float, float]:
        """Planned angle (rad), rate (rad/s) and acceleration (rad/s^2) about y at ``t_s``."""
        if t_s >= self.t_end_s or self.tf_s == 0:
            theta_end = 2.0 * math.asin(float(self.q2[-1]))
            rate = float(self.omega_rad_s[-1])
            return theta_end + rate * (max(t_s, self.t_end_s) - self.t_end_s), rate, 0.0
        t = max(0.0, t_s - self.t0_s)
        scale = 2.0 / self.tf_s
        nu, dnu, ddnu = (float(legendre.legval(scale * t - 1.0, c)) * scale**k for k, c in enumerate(_nu_series(self)))
        c0, c1, c2, c3 = self.prey.tolist()
        qp, dqp, ddqp = c0 + t * (c1 + t * (c2 + t * c3)), c1 + t * (2 * c2 + 3 * c3 * t), 2 * c2 + 6 * c3 * t
        arm = qp - self.q_ref
        q = self.q_ref + nu * arm
        return _angle_derivatives(q, dnu * arm + nu * dqp, ddnu * arm + 2.0 * dnu * dqp + nu * ddqp)

    @classmethod
    def hold(cls, q2: float, t0_s: float) -> PlannedPath:
        """Hold ``q2`` at rest from ``t0_s`` on."""
        zero = np.zeros(1)
        return cls(PlanStatus.OK, "", t0_s, 0.0, np.array([t0_s]), np.array([q2]), zero, zero, np.ones(1), 0.0,
                   np.array([q2, 0.0, 0.0, 0.0]), 2.0)


def _nu_series(path: PlannedPath) -> tuple[NDArray, NDArray, NDArray]:
    """Legendre coefficients (in tau) of nu(tau) and of its first two derivatives (cached)."""
    cached = path.__dict__.get("_nu_series")
    if cached is None:
        tau = 2.0 * (path.times_s - path.t0_s) / path.tf_s - 1.0
        c = legendre.legfit(tau, path.nu, path.nu.size - 1)
        cached = (c, legendre.legder(c, 1), legendre.legder(c, 2))
        object.__setattr__(path, "_nu_series", cached)
    return cached


def _angle_derivatives(q: float, dq: float, ddq: float) -> tuple[float, float, float]:
    """theta = 2 asin(q2) and its time derivatives from those of q2."""
    q = min(1.0, max(-1.0, q))
    root = math.sqrt(max(1e-300, 1.0 - q * q))
    return 2.0 * math.asin(q), 2.0 * dq / root, 2.0 * ddq / root + 2.0 * q * dq * dq / root**3


def prey_cubic(start: Boundary, end: Boundary, tf_s: float) -> NDArray[np.float64]:
    """Coefficients C0..C3 of the prey path ``q_p(t) = C0 + C1 t + C2 t^2 + C3 t^3`` (eq. 5.35-5.38)."""
    c0, c1 = start.q2, start.q2_dot
    c2 = (3.0 * (end.q2 - c0) - (2.0 * c1 + end.q2_dot) * tf_s) / tf_s**2
    c3 = (end.q2_dot - c1 - 2.0 * c2 * tf_s) / (3.0 * tf_s**2)
    return np.array([c0, c1, c2, c3])


class _Problem:
    """The discretised VMC problem of one slew: path, current and energy from the free PCPs."""

    def __init__(self, sat: CubeSat, start: Boundary, end: Boundary, tf_s: float, grid: LGLGrid, q_ref: float):
        self.sat, self.start, self.end, self.tf, self.grid, self.q_ref = sat, start, end, tf_s, grid, q_ref
        t = time_nodes(grid, 0.0, tf_s)
        self.prey = c = prey_cubic(start, end, tf_s)
        self.q_prey = c[0] + t * (c[1] + t * (c[2] + t * c[3]))
        self.dq_prey = c[1] + t * (2.0 * c[2] + t * 3.0 * c[3])
        self.diff = grid.diff * (2.0 / tf_s)
        self.arm = self.q_prey - q_ref  # q_p,i - q_r

    def nu(self, free: NDArray) -> NDArray[np.float64]:
        """All N PCPs: 1 at the ends, nu_2 and nu_{N-1} solved from the end rates (eq. 5.11-5.12)."""
        n, d = self.grid.n, self.diff
        nu = np.ones(n)
        nu[2:n - 2] = free
        rows = (0, n - 1)
        lhs = np.array([[d[r, 1], d[r, n - 2]] for r in rows])
        rhs = np.empty(2)
        for k, (r, q_dot) in enumerate(zip(rows, (self.start.q2_dot, self.end.q2_dot), strict=True)):
            rest = d[r] @ nu - d[r, 1] * nu[1] - d[r, n - 2] * nu[n - 2]
            rhs[k] = (q_dot - nu[r] * self.dq_prey[r]) / self.arm[r] - rest
        nu[[1, n - 2]] = np.linalg.solve(lhs, rhs)
        return nu

    def path(self, free: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """(nu, q2, omega, current) at the nodes."""
        nu = self.nu(free)
        q2 = self.q_ref + nu * self.arm
        q2_dot = (self.diff @ nu) * self.arm + nu * self.dq_prey
        omega = 2.0 * q2_dot / np.sqrt(np.clip(1.0 - q2 * q2, 1e-12, None))
        sat = self.sat
        authority = sat.moment_per_amp * sat.field_t * (1.0 - 2.0 * q2 * q2)
        current = sat.j22 * (self.diff @ omega) / np.where(np.abs(authority) > 1e-15, authority, 1e-15)
        return nu, q2, omega, current

    def cost(self, current: NDArray) -> float:
        return float(0.5 * self.sat.resistance_ohm * 0.5 * self.tf * (self.grid.weights @ current**2))


def plan_path(cubesat: CubeSat, start: Boundary, end: Boundary, t0_s: float, tf_s: float,
              options: PlannerOptions | None = None) -> PlannedPath:
    """The minimum-energy VMC path from ``start`` at ``t0_s`` to ``end`` at ``t0_s + tf_s``.

    Returns
    -------
    PlannedPath
        Status OK (bounds met, optimiser converged), NOT_CONVERGED (bounds met, optimiser
        stopped early: the best feasible point) or INFEASIBLE (the current bound cannot be met in
        ``tf_s``: the reason gives the peak current the best path needs).

    Raises
    ------
    InvalidInputError
        If ``tf_s`` is not positive or a boundary q2 is outside (-1/sqrt 2, 1/sqrt 2), where the
        coil has no authority.
    """
    options = options or PlannerOptions()
    if not (math.isfinite(tf_s) and tf_s > 0):
        raise InvalidInputError(f"tf_s must be a positive duration (s), got {tf_s!r}")
    for name, b in (("start", start), ("end", end)):
        if not (math.isfinite(b.q2) and abs(b.q2) < math.sqrt(0.5) and math.isfinite(b.omega_rad_s)):
            raise InvalidInputError(f"{name}.q2 must lie in (-0.707, 0.707) (coil authority 1 - 2 q2^2 > 0) "
                                    f"with a finite rate, got {b!r}")
    problem = _Problem(cubesat, start, end, float(tf_s), lgl_grid(options.n_nodes), options.q_ref)
    free, converged = _optimise(problem, options)
    nu, q2, omega, current = problem.path(free)
    status, reason = _judge(cubesat, q2, current, converged)
    return PlannedPath(status, reason, float(t0_s), float(tf_s), time_nodes(problem.grid, t0_s, tf_s),
                       q2, omega, current, nu, problem.cost(current), problem.prey, options.q_ref)


def _optimise(problem: _Problem, options: PlannerOptions) -> tuple[NDArray, bool]:
    """SLSQP over the free PCPs from nu = 1 (the prey path); the solution and whether it converged."""
    i_max = problem.sat.max_current_a
    scale = 1.0 / (problem.cost(np.full(problem.grid.n, i_max)) or 1.0)

    def cost(free):
        return scale * problem.cost(problem.path(free)[3])

    def bounds(free):
        _, q2, _, current = problem.path(free)
        return np.concatenate([1.0 - current / i_max, 1.0 + current / i_max, 1.0 - q2, 1.0 + q2])

    x0 = np.ones(problem.grid.n - 4)
    if x0.size == 0:
        return x0, True
    found = minimize(cost, x0, method="SLSQP", constraints=[{"type": "ineq", "fun": bounds}],
                     options={"maxiter": options.max_iter, "ftol": options.ftol})
    return np.asarray(found.x, dtype=float), bool(found.success)


def _judge(sat: CubeSat, q2: NDArray, current: NDArray, converged: bool) -> tuple[PlanStatus, str]:
    peak = float(np.max(np.abs(current)))
    if peak > sat.max_current_a * (1 + BOUND_SLACK) or float(np.max(np.abs(q2))) > 1.0:
        return PlanStatus.INFEASIBLE, f"the path needs {peak:.3f} A, above the {sat.max_current_a:g} A limit"
    if not converged:
        return PlanStatus.NOT_CONVERGED, "SLSQP stopped before converging (bounds met)"
    return PlanStatus.OK, ""
