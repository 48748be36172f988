"""The compiled loops of :mod:`._refine` (numba): the pose fit's least-squares system, its
Gauss-Newton iterations and the deleted residuals of its stars (the final fit's re-match, its
cone of catalog stars and the lens inversion are in :mod:`._match_kernel`); the equal-weight
q-method that both the pattern search (:mod:`._quad_kernel`) and a solve's final
attitude use, and what a solution reports of that attitude (residuals, covariance, RA / Dec / roll).

One projection model covers the whole camera: Brown-Conrady distortion with coefficients
``dist`` = (k1, k2, k3, p1, p2) as in :class:`startrack.camera.Camera` (all zero: pinhole).
Camera parameters come in as plain floats and that array, so the functions know nothing of
:class:`~startrack.camera.Camera`.

Kept apart so that importing startrack does not import numba; :mod:`._refine` loads this module
on first use. Compiled functions are cached on disk (``cache=True``); all arrays are float64 and
C-contiguous (the one signature :func:`.refine.warm_up_pose` compiles).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_EPS = float(np.finfo(np.float64).eps)
SINGULAR_PIVOT = 1e-12
"""A Cholesky pivot at most this share of its diagonal element counts as zero: the column is a
combination of the earlier ones up to rounding (1 - R^2 of that regression)."""


@njit(cache=True)
def _project(vx, vy, vz, dist):
    """Pinhole coordinates (a, b) = (v_x, v_y) / v_z of a camera vector, the same through the
    distortion (a_d, b_d), and the distortion's Jacobian d(a_d, b_d) / d(a, b) as
    (daa, dab, dba, dbb): eight floats (the equations of :mod:`startrack.camera`)."""
    k1, k2, k3, p1, p2 = dist[0], dist[1], dist[2], dist[3], dist[4]
    a, b = vx / vz, vy / vz
    r2 = a * a + b * b
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    ad = a * radial + 2.0 * p1 * a * b + p2 * (r2 + 2.0 * a * a)
    bd = b * radial + p1 * (r2 + 2.0 * b * b) + 2.0 * p2 * a * b
    dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)  # d radial / d r2
    daa = radial + a * dradial * 2.0 * a + 2.0 * p1 * b + p2 * 6.0 * a
    dab = a * dradial * 2.0 * b + 2.0 * p1 * a + p2 * 2.0 * b
    dba = b * dradial * 2.0 * a + p1 * 2.0 * a + 2.0 * p2 * b
    dbb = radial + b * dradial * 2.0 * b + p1 * 6.0 * b + 2.0 * p2 * a
    return a, b, ad, bd, daa, dab, dba, dbb


FREE_FOCAL, FREE_ASPECT, FREE_K1, FREE_K2 = 0, 1, 2, 3
"""Positions in the ``free`` flags (int64 array (4,), 1 = fitted) of the parameters beyond the
rotation, in the order their columns follow the rotation's three: ln f (fx and fy together),
ln(fy / fx) (fy alone, the pixel aspect), k1, k2."""


@njit(cache=True)
def n_parameters(free) -> int:
    """Parameters of a fit: the rotation's three and one per set flag of ``free`` (4,)."""
    return 3 + free[0] + free[1] + free[2] + free[3]


@njit(cache=True)
def fill_system(cam_vec, offset, fx, fy, dist, free, out):
    """Write the least-squares system of a fit to ``out`` (n_parameters(free) + 1, 2N).

    Rows: the transposed Jacobian of the predicted pixels (x_0, ..., x_N-1, y_0, ..., y_N-1)
    of camera vectors ``cam_vec`` (3, N) with respect to (small rotation of the camera frame,
    then the free parameters of :data:`FREE_FOCAL` ...) and, last, the residuals (detected minus
    predicted pixels). ``offset`` (2, N) holds the detected positions minus the principal point
    (pixels), ``fx``, ``fy`` the focal lengths (pixels).

    A rotation d moves a camera vector v to v + d x v; for the pinhole coordinates u = (a, b)
    that is du/dd_x = (-b a, -b b - 1), du/dd_y = (a a + 1, a b) and du/dd_z = (-b, a), then
    through the distortion's 2 x 2 Jacobian and the focal lengths. d/d ln f is the distorted
    point itself, d/d ln(fy / fx) its y part, d/d k1 is u r^2 and d/d k2 is u r^4.
    """
    n = cam_vec.shape[1]
    last = n_parameters(free)
    for i in range(n):
        a, b, ad, bd, daa, dab, dba, dbb = _project(cam_vec[0, i], cam_vec[1, i], cam_vec[2, i], dist)
        turn_a = (-b * a, a * a + 1.0, -b)
        turn_b = (-b * b - 1.0, a * b, a)
        for k in range(3):
            out[k, i] = fx * (daa * turn_a[k] + dab * turn_b[k])
            out[k, n + i] = fy * (dba * turn_a[k] + dbb * turn_b[k])
        r2 = a * a + b * b
        row = 3
        if free[FREE_FOCAL]:
            out[row, i], out[row, n + i] = fx * ad, fy * bd
            row += 1
        if free[FREE_ASPECT]:
            out[row, i], out[row, n + i] = 0.0, fy * bd
            row += 1
        if free[FREE_K1]:
            out[row, i], out[row, n + i] = fx * (a * r2), fy * (b * r2)
            row += 1
        if free[FREE_K2]:
            out[row, i], out[row, n + i] = fx * (a * r2 * r2), fy * (b * r2 * r2)
        out[last, i] = fx * (offset[0, i] / fx - ad)
        out[last, n + i] = fy * (offset[1, i] / fy - bd)


@njit(cache=True)
def _gram(rows):
    """``rows @ rows.T`` of a (p, M) array, shape (p, p)."""
    p, m = rows.shape
    gram = np.empty((p, p))
    for i in range(p):
        for j in range(i + 1):
            total = 0.0
            for k in range(m):
                total += rows[i, k] * rows[j, k]
            gram[i, j] = total
            gram[j, i] = total
    return gram


@njit(cache=True)
def _cholesky(normal, p):
    """Lower Cholesky factor (p, p) of ``normal[:p, :p]``, or None when the matrix is singular:
    a pivot is not positive (as LAPACK's dpotrf reports it), NaN, or no more than rounding
    (:data:`SINGULAR_PIVOT`), which would otherwise give an arbitrary step along the null space."""
    low = np.zeros((p, p))
    for j in range(p):
        pivot = normal[j, j]
        for k in range(j):
            pivot -= low[j, k] * low[j, k]
        if not pivot > SINGULAR_PIVOT * normal[j, j]:
            return None
        low[j, j] = math.sqrt(pivot)
        for i in range(j + 1, p):
            total = normal[i, j]
            for k in range(j):
                total -= low[i, k] * low[j, k]
            low[i, j] = total / low[j, j]
    return low


@njit(cache=True)
def _cho_solve(low, rows, col, out):
    """Solve ``low @ low.T @ out = rows[:p, col]`` for the Cholesky factor ``low`` (p, p): the
    right-hand side is column ``col`` of ``rows`` (at least p rows)."""
    p = low.shape[0]
    for i in range(p):
        total = rows[i, col]
        for k in range(i):
            total -= low[i, k] * out[k]
        out[i] = total / low[i, i]
    for i in range(p - 1, -1, -1):
        total = out[i]
        for k in range(i + 1, p):
            total -= low[k, i] * out[k]
        out[i] = total / low[i, i]


@njit(cache=True)
def _step(system, delta):
    """The Gauss-Newton step of a system (p + 1, M) from :func:`fill_system`, written to
    ``delta`` (p,): the normal equations by Cholesky, least squares if they are singular."""
    p = system.shape[0] - 1
    normal = _gram(system)
    low = _cholesky(normal, p)
    if low is not None:
        _cho_solve(low, normal, p, delta)
        return
    if system.shape[1] == 0:  # no stars: no step
        delta[:] = 0.0
        return
    jac_t = np.ascontiguousarray(system[:p].T)
    rcond = _EPS * max(system.shape[1], p)  # numpy's default (rcond=None)
    delta[:] = np.linalg.lstsq(jac_t, system[p].copy(), rcond)[0]


@njit(cache=True)
def _turn(delta, matrix):
    """Rotate ``matrix`` (3, 3) in place by the rotation vector ``delta[:3]`` (radians), on the
    left: ``R @ matrix`` with R = cos t I + sin t [k]_x + (1 - cos t) k k^T."""
    x, y, z = delta[0], delta[1], delta[2]
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-15:
        return
    x, y, z = x / angle, y / angle, z / angle
    s, c = math.sin(angle), math.cos(angle)
    t = 2.0 * math.sin(0.5 * angle) ** 2  # 1 - cos, without the cancellation
    rot = ((c + t * x * x, t * x * y - s * z, t * x * z + s * y),
           (t * x * y + s * z, c + t * y * y, t * y * z - s * x),
           (t * x * z - s * y, t * y * z + s * x, c + t * z * z))
    old = matrix.copy()
    for i in range(3):
        for j in range(3):
            row = rot[i]
            matrix[i, j] = row[0] * old[0, j] + row[1] * old[1, j] + row[2] * old[2, j]


@njit(cache=True)
def _rotate(matrix, ref, cam_vec):
    """Camera vectors ``cam_vec`` (3, K) = ``matrix`` (3, 3) @ ``ref.T`` for ICRS vectors ``ref`` (K, 3)."""
    for i in range(ref.shape[0]):
        for r in range(3):
            cam_vec[r, i] = matrix[r, 0] * ref[i, 0] + matrix[r, 1] * ref[i, 1] + matrix[r, 2] * ref[i, 2]


@njit(cache=True)
def _moved_px(delta, free, fx, corner):
    """Largest image motion (pixels) a step ``delta`` (p,) causes, roughly: rotation times focal
    length ``fx``, plus the focal, aspect, k1 and k2 changes at the image corner (``corner``
    pixels from the centre)."""
    moved = max(abs(delta[0]), abs(delta[1]), abs(delta[2])) * fx * 2.0
    reach = corner / fx  # the corner in pinhole units
    gains = (corner, corner, corner * reach**2, corner * reach**4)
    row = 3
    for k in range(4):
        if free[k]:
            moved += abs(delta[row]) * gains[k]
            row += 1
    return moved


@njit(cache=True)
def _residual_px(cam_vec, offset, fx, fy, dist):
    """Pixel distance (K,) between the detected positions (``offset`` (2, K), from the principal
    point) and the projections of camera vectors ``cam_vec`` (3, K)."""
    out = np.empty(cam_vec.shape[1])
    for i in range(out.size):
        _, _, ad, bd, _, _, _, _ = _project(cam_vec[0, i], cam_vec[1, i], cam_vec[2, i], dist)
        out[i] = math.hypot(offset[0, i] - fx * ad, offset[1, i] - fy * bd)
    return out


@njit(cache=True)
def _apply_step(delta, free, fx, fy, dist):
    """The focal lengths (fx, fy) after a step ``delta`` of the free parameters (rows 3...);
    updates k1 and k2 in ``dist`` in place."""
    row = 3
    if free[FREE_FOCAL]:
        scale = math.exp(delta[row])
        fx, fy = fx * scale, fy * scale
        row += 1
    if free[FREE_ASPECT]:
        fy = fy * math.exp(delta[row])
        row += 1
    if free[FREE_K1]:
        dist[0] += delta[row]
        row += 1
    if free[FREE_K2]:
        dist[1] += delta[row]
    return fx, fy


MAX_LN_FOCAL_STEP = math.log(10.0)
"""A Gauss-Newton step that scales the focal length by more than 10 (or holds a NaN) diverges: a
solve's fits start from a verified candidate's focal length, a few per cent from the truth. Such
steps came from the k1 scan's strongest barrels on a 130 deg field (lenses folding inside the
frame), and step after step drove the focal length to zero (a ZeroDivisionError)."""


@njit(cache=True)
def _diverging(delta, free):
    """Whether the step ``delta`` (p,) is not finite or scales the focal length (when
    ``free[FREE_FOCAL]``) by more than a factor exp(:data:`MAX_LN_FOCAL_STEP`)."""
    for value in delta:
        if not math.isfinite(value):
            return True
    return bool(free[FREE_FOCAL]) and abs(delta[3]) > MAX_LN_FOCAL_STEP


@njit(cache=True)
def fit(matrix, ref, x, y, fx, fy, cx, cy, dist, free, corner, max_iter, converged_px):
    """Gauss-Newton fit of an attitude and the parameters flagged in ``free`` (4,: ln f,
    ln(fy / fx), k1, k2; see :data:`FREE_FOCAL`).

    ``matrix`` (3, 3) is the starting ICRS-to-camera rotation matrix, ``ref`` (K, 3) the ICRS unit
    vectors of the stars, ``x``, ``y`` (K,) their detected positions (pixels); the camera has
    focal lengths ``fx``, ``fy`` and principal point ``cx``, ``cy`` (pixels) and distortion
    coefficients ``dist`` (5,). Iterates at most ``max_iter`` times, stopping when
    :func:`_moved_px` of a step is below ``converged_px``, or before a step that diverges
    (:func:`_diverging`: the state is then the last one before it).
    Returns (matrix (3, 3), fx, fy, k1, k2, residual distance (K,) in pixels).
    """
    matrix, dist = matrix.copy(), dist.copy()
    offset = np.empty((2, ref.shape[0]))
    for i in range(ref.shape[0]):
        offset[0, i], offset[1, i] = x[i] - cx, y[i] - cy
    cam_vec = np.empty((3, ref.shape[0]))
    n_params = n_parameters(free)
    system = np.empty((n_params + 1, 2 * ref.shape[0]))
    delta = np.empty(n_params)
    for _ in range(max_iter):
        _rotate(matrix, ref, cam_vec)
        fill_system(cam_vec, offset, fx, fy, dist, free, system)
        _step(system, delta)
        if _diverging(delta, free):
            break
        _turn(delta, matrix)
        fx, fy = _apply_step(delta, free, fx, fy, dist)
        if _moved_px(delta, free, fx, corner) < converged_px:
            break
    _rotate(matrix, ref, cam_vec)
    return matrix, fx, fy, dist[0], dist[1], _residual_px(cam_vec, offset, fx, fy, dist)


@njit(cache=True)
def _leverage(inverse, system, i, j):
    """``J_i^T (J^T J)^-1 J_j`` for columns i and j of the Jacobian rows ``system[:p]`` and the
    inverse normal matrix ``inverse`` (p, p)."""
    p, total = inverse.shape[0], 0.0
    for a in range(p):
        spread = 0.0
        for b in range(p):
            spread += inverse[a, b] * system[b, j]
        total += system[a, i] * spread
    return total


@njit(cache=True)
def deleted_residuals(system):
    """Deleted residuals (pixels, (N,)) of the stars of a system (p + 1, 2N) from :func:`fill_system`.

    For star i with residual r_i (2,) and Jacobian rows J_i (2, p): ``|(I - H_ii)^-1 r_i|`` with
    ``H_ii = J_i (J^T J)^-1 J_i^T``. All inf if J^T J is singular; inf for a star whose
    ``det(I - H_ii)`` is below 1e-9.
    """
    p, n = system.shape[0] - 1, system.shape[1] // 2
    out = np.full(n, np.inf)
    low = _cholesky(_gram(system[:p]), p)
    if low is None:
        return out
    unit, inverse = np.eye(p), np.empty((p, p))
    for j in range(p):
        _cho_solve(low, unit, j, inverse[j])  # symmetric: row j is column j
    for i in range(n):
        keep_xx = 1.0 - _leverage(inverse, system, i, i)  # I - H_ii, symmetric
        keep_yy = 1.0 - _leverage(inverse, system, n + i, n + i)
        keep_xy = -_leverage(inverse, system, i, n + i)
        det = keep_xx * keep_yy - keep_xy * keep_xy
        if det > 1e-9:
            rx, ry = system[p, i], system[p, n + i]
            out[i] = math.hypot(keep_yy * rx - keep_xy * ry, keep_xx * ry - keep_xy * rx) / det
    return out


@njit(cache=True)
def q_method(obs, ref):
    """Davenport's q-method for equal weights (as :mod:`startrack.attitude._qmethod`; Huffman 2006
    §6.1.3): the scalar-last quaternion (4,) of R with R ref_i ~ obs_i (rows of (N, 3) arrays of
    unit vectors) and R itself (3, 3). The four-star fits of the pattern search and the final
    attitude of a solve."""
    b = np.zeros((3, 3))
    for i in range(obs.shape[0]):
        for j in range(3):
            for k in range(3):
                b[j, k] += obs[i, j] * ref[i, k]
    sigma = b[0, 0] + b[1, 1] + b[2, 2]
    davenport = np.empty((4, 4))
    for j in range(3):
        for k in range(3):
            davenport[j, k] = b[j, k] + b[k, j] - (sigma if j == k else 0.0)
    davenport[0, 3] = davenport[3, 0] = b[2, 1] - b[1, 2]
    davenport[1, 3] = davenport[3, 1] = b[0, 2] - b[2, 0]
    davenport[2, 3] = davenport[3, 2] = b[1, 0] - b[0, 1]
    davenport[3, 3] = sigma
    quat = np.ascontiguousarray(np.linalg.eigh(davenport)[1][:, 3])  # largest eigenvalue last
    return quat, _quat_matrix(quat)


@njit(cache=True)
def _quat_matrix(q):
    """Rotation matrix (3, 3) of a unit scalar-last quaternion (4,), scipy's convention."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@njit(cache=True)
def _times(matrix, vectors, i):
    """``matrix`` (3, 3) times row i of ``vectors`` (S, 3), as three floats."""
    x, y, z = vectors[i, 0], vectors[i, 1], vectors[i, 2]
    return (matrix[0, 0] * x + matrix[0, 1] * y + matrix[0, 2] * z,
            matrix[1, 0] * x + matrix[1, 1] * y + matrix[1, 2] * z,
            matrix[2, 0] * x + matrix[2, 1] * y + matrix[2, 2] * z)


@njit(cache=True)
def _inverse_3x3(m):
    """Inverse (3, 3) of a non-singular 3 x 3 matrix by its adjugate (no LAPACK to compile)."""
    adj = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            r0, r1 = (j + 1) % 3, (j + 2) % 3
            c0, c1 = (i + 1) % 3, (i + 2) % 3
            adj[i, j] = m[r0, c0] * m[r1, c1] - m[r0, c1] * m[r1, c0]
    det = m[0, 0] * adj[0, 0] + m[0, 1] * adj[1, 0] + m[0, 2] * adj[2, 0]
    return adj / det


@njit(cache=True)
def solution_terms(obs, ref, sigma_rad):
    """What a solution reports of equally weighted vector pairs: the q-method attitude
    (:func:`q_method`: scalar-last quaternion (4,), matrix (3, 3) with R ref_i ~ obs_i), each
    pair's residual angle (radians, (N,), ``atan2(|R ref x obs|, R ref . obs)``), the QUEST
    covariance (3, 3) of the camera-frame attitude error for a common per-axis error
    ``sigma_rad`` (:func:`startrack.attitude._covariance.covariance_batch`: sigma^2 / N times
    ``(I - sum w w^T / N)^-1``), and the boresight RA, Dec and roll (radians, as
    :func:`startrack.frames.radec_roll_from_rotation`)."""
    quat, matrix = q_method(obs, ref)
    n = obs.shape[0]
    residual = np.empty(n)
    info = np.eye(3)
    for i in range(n):
        p0, p1, p2 = _times(matrix, ref, i)
        cx = p1 * obs[i, 2] - p2 * obs[i, 1]
        cy = p2 * obs[i, 0] - p0 * obs[i, 2]
        cz = p0 * obs[i, 1] - p1 * obs[i, 0]
        residual[i] = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz),
                                 p0 * obs[i, 0] + p1 * obs[i, 1] + p2 * obs[i, 2])
        for j in range(3):
            for k in range(3):
                info[j, k] -= obs[i, j] * obs[i, k] / n
    covariance = _inverse_3x3(info) * (sigma_rad * sigma_rad / n)
    return quat, matrix, residual, covariance, _radec_roll(matrix)


@njit(cache=True)
def _radec_roll(matrix):
    """Boresight RA in [0, 2 pi), Dec and roll in [0, 2 pi) (radians) of an ICRS-to-camera matrix
    (3, 3): the formulas of :func:`startrack.frames.radec_roll_from_rotation`."""
    x, y, z = matrix[2, 0], matrix[2, 1], matrix[2, 2]
    ra = _wrap_2pi(math.atan2(y, x))
    dec = math.atan2(z, math.hypot(x, y))
    y0, y1, y2 = matrix[1, 0], matrix[1, 1], matrix[1, 2]  # camera +y in ICRS; up is -y
    sr, cr, sd, cd = math.sin(ra), math.cos(ra), math.sin(dec), math.cos(dec)
    up_east = y0 * sr - y1 * cr
    up_north = y0 * sd * cr + y1 * sd * sr - y2 * cd
    return ra, dec, _wrap_2pi(-math.atan2(up_east, up_north))


@njit(cache=True)
def _wrap_2pi(angle):
    """An angle (radians) in [0, 2 pi), as :func:`startrack.frames._wrap_2pi`."""
    two_pi = 2.0 * math.pi
    wrapped = angle % two_pi
    return 0.0 if wrapped >= two_pi else wrapped
