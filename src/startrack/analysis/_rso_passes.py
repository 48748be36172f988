"""Observation opportunities of an RSO from a spinning camera in orbit (Sease 2013 Tables 4.3-4.4).

Sease 2013's 10-orbit simulation (Sease 2013 Chapter 4): the camera's spacecraft and
the RSO fly the Keplerian orbits of Table 4.3 (two-body + J2, :class:`startrack.simulate.Orbit`);
the camera turns at a constant rate about its focal-plane y axis (0.05 rad/s) from the identity
attitude (quaternion [0 0 0 1]: camera axes = GCRS axes at the epoch), and "images were only
generated when the RSO was in view of the camera and not eclipsed by the Earth".

:func:`find_passes` lists those images. The camera takes back-to-back exposures from the epoch
(frame k from ``k * exposure_s``); an *opportunity* is a frame in which

- the RSO's sight line stays ``margin_px`` inside the image over the whole exposure (its
  positions at the start, middle and end, light time included);
- the RSO is outside the Earth's cylindrical shadow (seed eq. 2.15,
  :meth:`startrack.simulate.Snapshot.rso_lit`);
- neither the Sun nor the Earth is in the field (seed eqs. 2.16-2.19 with the boresight the
  camera +z axis, :meth:`startrack.simulate.Snapshot.bright_bodies`: within the half-diagonal
  field of view). An RSO hidden behind the Earth has the Earth in the field, so it is excluded
  by the same test.

The seed gives no epoch, camera or frame cadence; those are parameters here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy.time import Time, TimeDelta
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicHermiteSpline
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError
from ..simulate import R_EARTH_KM, RSO, KeplerElements, Orbit, OrbitalScene, Snapshot

SEASE2013_CAMERA_ELEMENTS = (6748.0, 0.0, 28.5, 0.0, 0.0, 0.0)
"""Table 4.3, camera spacecraft: a (km), e, i, RAAN, argument of perigee, true anomaly (deg)."""
SEASE2013_RSO_ELEMENTS = (7078.0, 0.0, 89.0, 0.0, 30.0, 120.0)
"""Table 4.3, the RSO (the row the table labels "Spacecraft")."""
KNOT_S = 10.0
"""Spacing of the propagated states that the candidate search interpolates (s)."""
PREFILTER_SLACK_RAD = math.radians(1.0)
"""The quick Earth test on the propagation grid keeps frames up to 1 deg inside the field's
edge; the exact test (:meth:`startrack.simulate.Snapshot.bright_bodies`) decides."""


@dataclass(frozen=True)
class Pass:
    """One observation opportunity.

    Attributes
    ----------
    index : int
        Its place among the opportunities of the scenario (time order).
    start_s : float
        Start of the exposure, seconds after the epoch.
    rot_start : Rotation
        ``rot_cam_from_icrs`` at the start of the exposure.
    snapshot : Snapshot
        The orbital geometry at mid-exposure (for :func:`startrack.simulate.render_stars`).
    range_km : float
        Observer-RSO distance at mid-exposure.
    """

    index: int
    start_s: float
    rot_start: Rotation
    snapshot: Snapshot
    range_km: float


def elements(values: ArrayLike, name: str) -> KeplerElements:
    """Keplerian elements from (a km, e, i, RAAN, argp, true anomaly deg), checked.

    Raises
    ------
    InvalidInputError
        Naming ``name`` when the elements are not six numbers or not a valid orbit.
    """
    vals = np.asarray(values, dtype=float)
    if vals.shape != (6,):
        raise InvalidInputError(f"{name}: six elements (a_km, e, i_deg, raan_deg, argp_deg, nu_deg) needed, "
                                f"got {vals.shape}")
    try:
        return KeplerElements.from_degrees(*(float(v) for v in vals))
    except InvalidInputError as exc:
        raise InvalidInputError(f"{name}: {exc}") from None


def camera_rotation(omega_cam_rad_s: ArrayLike, t_s: ArrayLike) -> Rotation:
    """``rot_cam_from_icrs`` at times ``t_s`` (N,) of a camera turning at a constant camera-frame
    rate from the identity attitude: ``exp(-[omega x] t)``."""
    omega = np.asarray(omega_cam_rad_s, dtype=float)
    return Rotation.from_rotvec(-np.outer(np.atleast_1d(t_s), omega))


def _in_image(camera: Camera, vectors_cam: NDArray, margin_px: float) -> NDArray[np.bool_]:
    x, y = camera.vector_to_pixel(vectors_cam)  # NaN behind the camera: not in the image
    return camera.in_image(x, y, margin_px)


def _earth_edge_rad(boresight: NDArray, observer_km: NDArray) -> NDArray[np.float64]:
    """Angle (N,) from each boresight (N, 3) to the nearest point of the Earth's limb."""
    nadir = -observer_km
    angle = np.arctan2(np.linalg.norm(np.cross(boresight, nadir), axis=1), np.sum(boresight * nadir, axis=1))
    return angle - np.arcsin(np.minimum(1.0, R_EARTH_KM / np.linalg.norm(nadir, axis=1)))


def _positions(orbit: Orbit, t_s: NDArray) -> NDArray[np.float64]:
    """Positions (N, 3) km at sorted times ``t_s`` (N,): the orbit propagated every
    :data:`KNOT_S` seconds and interpolated by cubic Hermite splines on positions and velocities
    (error well under a metre in LEO, far below a pixel)."""
    knots = np.arange(0.0, t_s[-1] + KNOT_S, KNOT_S)
    r, v = orbit.states(knots)
    return CubicHermiteSpline(knots, r, v, axis=0)(t_s)


def _candidates(observer: Orbit, target: Orbit, camera: Camera, omega: NDArray, exposure_s: float,
                duration_s: float, margin_px: float) -> NDArray[np.float64]:
    """Frame start times whose RSO path (geometric, no light time) stays in the image and whose
    field is clear of the Earth to within :data:`PREFILTER_SLACK_RAD`, on a grid of half
    exposures (the start, middle and end of every frame)."""
    grid = np.arange(0.0, duration_s + 0.25 * exposure_s, 0.5 * exposure_s)
    obs, rso = _positions(observer, grid), _positions(target, grid)
    rots = camera_rotation(omega, grid)
    x, y = camera.vector_to_pixel(rots.apply(rso - obs))
    inside = camera.in_image(x, y, margin_px)
    clear = _earth_edge_rad(rots.inv().apply([0.0, 0.0, 1.0]), obs) > (
        math.radians(camera.fov_diagonal_deg) / 2 - PREFILTER_SLACK_RAD)
    frames = (len(grid) - 1) // 2
    k = 2 * np.arange(frames)
    keep = inside[k] & inside[k + 1] & inside[k + 2] & clear[k + 1]
    return grid[k[keep]]


def find_passes(camera: Camera, observer: KeplerElements, rso: KeplerElements, epoch: Time, *,
                omega_cam_rad_s: ArrayLike = (0.0, 0.05, 0.0), exposure_s: float = 0.5,
                duration_s: float | None = None, orbits: float = 10.0, rso_mag: float = 4.0,
                margin_px: float = 20.0) -> list[Pass]:
    """The observation opportunities of the scenario (module docstring), in time order.

    Parameters
    ----------
    camera : Camera
    observer, rso : KeplerElements
        Orbits at ``epoch`` (GCRS axes), propagated with J2.
    epoch : astropy.time.Time
        Time of the elements and of the identity attitude.
    omega_cam_rad_s : array_like, shape (3,)
        The camera's rate (camera frame).
    exposure_s : float
        Exposure, also the frame interval (back-to-back frames).
    duration_s : float, optional
        Length of the scenario; default ``orbits`` periods of the observer.
    rso_mag : float
        The RSO's fixed V magnitude when lit.
    margin_px : float
        How far inside the image the RSO's path must stay.

    Returns
    -------
    list of Pass
    """
    if exposure_s <= 0 or margin_px < 0:
        raise InvalidInputError(f"exposure_s must be > 0 and margin_px >= 0, got {exposure_s}, {margin_px}")
    omega = np.asarray(omega_cam_rad_s, dtype=float)
    duration = observer.period_s * orbits if duration_s is None else float(duration_s)
    obs_orbit, rso_orbit = Orbit.from_elements(epoch, observer), Orbit.from_elements(epoch, rso)
    starts = _candidates(obs_orbit, rso_orbit, camera, omega, exposure_s, duration, margin_px)
    if not len(starts):
        return []
    scene = OrbitalScene(obs_orbit, (RSO(rso_orbit, 1, rso_mag),))
    mids = starts + exposure_s / 2
    snapshots = scene.snapshots(epoch + TimeDelta(mids, format="sec"))
    passes: list[Pass] = []
    for start, mid, snap in zip(starts, mids, snapshots, strict=True):
        rot_mid = camera_rotation(omega, mid)[0]
        boresight = rot_mid.inv().apply([0.0, 0.0, 1.0])
        los = snap.lines_of_sight(np.array([[-exposure_s / 2, 0.0, exposure_s / 2]]))[0]
        ends = camera_rotation(omega, start + np.array([0.0, exposure_s / 2, exposure_s])).apply(los)
        if (snap.rso_lit()[0] and not snap.bright_bodies(boresight, camera).corrupted
                and np.all(_in_image(camera, ends, margin_px))):
            passes.append(Pass(len(passes), float(start), camera_rotation(omega, start)[0], snap,
                               float(snap.rso_ranges_km()[0])))
    return passes
