"""Solve two-vector Wahba problems with ahrs's QUEST, Davenport and TRIAD (inside .venv-ahrs).

Usage::

    python ahrs_runner.py PROBLEMS.npz OUT.npz

``PROBLEMS.npz`` holds ``observed`` and ``reference`` (M, 2, 3) unit vectors (the rotation
sought maps reference onto observed). ahrs's solvers take two *observed* vectors and keep their
two *reference* vectors on the object (``g_q`` / ``m_q`` for QUEST and Davenport, ``v1`` / ``v2``
for TRIAD), so those are set per problem before each call; both pairs get equal weights. This
file must not import startrack. ahrs returns scalar-first quaternions (and a TRIAD matrix) of
the *passive* attitude (reference -> body frame transformation in Shuster's convention), i.e.
the transpose of the active rotation; the conversion to scipy's scalar-last active convention is
done here, and the benchmark checks it against the truth.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from ahrs.filters import QUEST, TRIAD, Davenport


def _active_from_ahrs_quat(q_wxyz: np.ndarray) -> np.ndarray:
    """Scalar-last quaternion of the active rotation from ahrs's scalar-first passive one."""
    return np.array([-q_wxyz[1], -q_wxyz[2], -q_wxyz[3], q_wxyz[0]])


def _quat_from_matrix(m: np.ndarray) -> np.ndarray:
    """Scalar-last quaternion of a rotation matrix (Shepperd's method), for TRIAD's matrix."""
    t = np.trace(m)
    cases = [t, m[0, 0], m[1, 1], m[2, 2]]
    k = int(np.argmax(cases))
    if k == 0:
        w = np.sqrt(1 + t) / 2
        vector = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]) / (4 * w)
        return np.append(vector, w)
    i, j, n = [(0, 1, 2), (1, 2, 0), (2, 0, 1)][k - 1]
    q = np.zeros(4)
    q[i] = np.sqrt(1 + 2 * m[i, i] - t) / 2
    q[j] = (m[j, i] + m[i, j]) / (4 * q[i])
    q[n] = (m[n, i] + m[i, n]) / (4 * q[i])
    q[3] = (m[n, j] - m[j, n]) / (4 * q[i])
    return q


def _solve_all(solver, observed, reference, set_refs, convert) -> tuple[np.ndarray, float]:
    out = np.zeros((len(observed), 4))
    t0 = time.perf_counter()
    for k in range(len(observed)):
        set_refs(solver, reference[k])
        out[k] = convert(solver.estimate(observed[k, 0], observed[k, 1]))
    return out, time.perf_counter() - t0


def _set_qd(solver, ref):
    solver.g_q, solver.m_q = ref[0], ref[1]


def _set_triad(solver, ref):
    solver.v1, solver.v2 = ref[0], ref[1]


def main(argv: list[str]) -> int:
    src, dst = argv
    with np.load(src) as npz:
        observed, reference = npz["observed"], npz["reference"]
    results = {}
    quest = QUEST(weights=np.array([0.5, 0.5]))
    davenport = Davenport(weights=np.ones(2))
    triad = TRIAD(v1=reference[0, 0], v2=reference[0, 1])
    # TRIAD returns the passive matrix A (b = A r): the active rotation's matrix is A itself.
    for name, solver, setter, convert in [
        ("quest", quest, _set_qd, _active_from_ahrs_quat),
        ("davenport", davenport, _set_qd, _active_from_ahrs_quat),
        ("triad", triad, _set_triad, _quat_from_matrix),
    ]:
        quat, elapsed = _solve_all(solver, observed, reference, setter, convert)
        results[f"{name}_quat"], results[f"{name}_time_s"] = quat, np.array(elapsed)
    np.savez(dst, **results)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
