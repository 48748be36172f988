"""One scene through every head of a camera rig: images, or star lists, with their truth.

The body turns at ``rot_body_from_icrs`` (at mid-exposure) with a body-frame rate; head h sees
``rot_cam_from_body_h * rot_body_from_icrs`` and turns at ``rot_cam_from_body_h.apply(rate)``. Each
head is rendered as an ordinary frame (:func:`startrack.simulate.simulate_frame`, its own noise
stream spawned from ``rng``); the fields of a split detector are rendered together
(:func:`.split_fov.simulate_split_frame`). With :class:`startrack.multihead._exclusion.BrightBodies`
(the Sun, the Earth and the Moon seen from the observer) a head whose exclusion cone a body enters
is *blinded*: its detector is flooded with stray light (a background of twice the full well, so
every pixel saturates and no star is detected) and its truth says which body did it.

:func:`rig_star_lists` is the quick path: catalog stars projected through each head's camera with
Gaussian centroid noise (the head's ``centroid_sigma_px`` unless given), optional drop-outs and
false stars, brightest first, as a star tracker's detector would hand them over.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError, checked_rng
from ..rig import CameraRig, RigHead
from ._noise import NoiseModel
from ._radiometry import Sensor
from ._scene import DEFAULT_SENSOR, FrameTiming, SimulatedImage
from ._sky import DEFAULT_MAX_MAG, SkyModel, simulate_frame
from ._split_fov import SplitFieldFrame, simulate_split_frame

FLUX_MAG0 = 1.0e6
"""Flux of a magnitude-0 star in the star lists (arbitrary units, as :mod:`startrack.analysis._starlists`)."""

BLINDING_WELLS = 2.0
"""A blinded detector's stray-light background, in full wells."""


@functools.lru_cache(maxsize=8)
def rig_sky(max_mag: float, epoch_jyear: float | None) -> SkyModel:
    """Hipparcos stars to ``max_mag`` (V) at an epoch, kept per process."""
    return SkyModel.from_catalog(max_mag=float(max_mag), epoch_jyear=epoch_jyear)


@dataclass(frozen=True)
class HeadStarList:
    """One head's simulated star list, brightest first: measured x, y (px), flux, the HIP number of
    each entry (-1 for a false star) and the true positions (NaN for false stars)."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    flux: NDArray[np.float64]
    hip: NDArray[np.int64]
    true_x: NDArray[np.float64]
    true_y: NDArray[np.float64]
    blinded_by: str = ""

    def __len__(self) -> int:
        return int(self.x.size)

    @property
    def stars(self) -> tuple[NDArray, NDArray, NDArray]:
        """``(x, y, flux)``, the form :func:`startrack.solve_rig` takes."""
        return self.x, self.y, self.flux


def head_star_list(camera: Camera, rot_cam_from_icrs: Rotation, sky: SkyModel, rng: np.random.Generator, *,
                   sigma_px: float, max_stars: int = 40, drop_fraction: float = 0.0,
                   false_stars: int = 0) -> HeadStarList:
    """Catalog stars of ``sky`` in the camera's image with centroid noise ``sigma_px`` (px per axis),
    a fraction dropped at random, ``false_stars`` added uniformly (magnitudes within 3 of the
    faintest), sorted by magnitude and cut to ``max_stars``."""
    boresight = rot_cam_from_icrs.inv().apply([0.0, 0.0, 1.0])
    idx = sky.cone(boresight, np.radians(camera.fov_diagonal_deg) / 2.0 * 1.02)
    tx, ty = camera.vector_to_pixel(rot_cam_from_icrs.apply(sky.vectors_icrs[idx]).reshape(-1, 3))
    x, y = tx + rng.normal(0.0, sigma_px, tx.shape), ty + rng.normal(0.0, sigma_px, ty.shape)
    inside = np.flatnonzero(camera.in_image(x, y) & camera.in_image(tx, ty))
    inside = inside[rng.random(inside.size) >= drop_fraction]
    n_false = int(false_stars)
    fx, fy = rng.uniform(-0.5, camera.width - 0.5, n_false), rng.uniform(-0.5, camera.height - 0.5, n_false)
    faint = float(sky.mags.max()) if len(sky) else 6.0
    mags = np.concatenate([sky.mags[idx[inside]], rng.uniform(faint - 3.0, faint, n_false)])
    order = np.argsort(mags, kind="stable")[:max_stars]
    nan = np.full(n_false, np.nan)
    return HeadStarList(x=np.concatenate([x[inside], fx])[order], y=np.concatenate([y[inside], fy])[order],
                        flux=FLUX_MAG0 * 10.0 ** (-0.4 * mags[order]),
                        hip=np.concatenate([sky.ids[idx[inside]], np.full(n_false, -1)])[order].astype(np.int64),
                        true_x=np.concatenate([tx[inside], nan])[order],
                        true_y=np.concatenate([ty[inside], nan])[order])


def _empty_list(reason: str) -> HeadStarList:
    none = np.zeros(0)
    return HeadStarList(none, none, none, np.zeros(0, dtype=np.int64), none, none, reason)


def rig_star_lists(rig: CameraRig, rot_body_from_icrs: Rotation, *, max_mag: float = 6.0,
                   epoch_jyear: float = 2000.0, rng: np.random.Generator | int | None = None,
                   sigma_px: float | None = None, max_stars: int = 40, drop_fraction: float = 0.0,
                   false_stars: int = 0, bodies=None) -> dict[str, HeadStarList]:
    """Each head's star list at a body attitude (module docstring).

    Parameters
    ----------
    rig : CameraRig
    rot_body_from_icrs : Rotation
    max_mag : float
        Faintest catalog star in the lists (V).
    epoch_jyear : float
    rng : Generator, int or None
        One stream for all heads, drawn head by head in the rig's order.
    sigma_px : float, optional
        Centroid noise of every head (px); default each head's ``centroid_sigma_px``.
    max_stars, drop_fraction, false_stars
        Per head: list length, share of real stars left out, false stars added.
    bodies : BrightBodies, optional
        Sun, Earth and Moon: a blinded head gets an empty list (``blinded_by`` names the body).

    Returns
    -------
    dict of str to HeadStarList
    """
    from ..multihead import blinded_by

    rng = checked_rng(rng)
    sky = rig_sky(max_mag, epoch_jyear)
    out = {}
    for head in rig:
        rot = head.rot_cam_from_icrs(rot_body_from_icrs)
        blind = blinded_by(head, bodies, rot.inv().apply([0.0, 0.0, 1.0]))
        sigma = head.centroid_sigma_px if sigma_px is None else float(sigma_px)
        out[head.name] = _empty_list(blind) if blind else head_star_list(
            head.camera, rot, sky, rng, sigma_px=sigma, max_stars=max_stars, drop_fraction=drop_fraction,
            false_stars=false_stars)
    return out


@dataclass(frozen=True)
class RigFrame:
    """One exposure of every detector of a rig.

    Attributes
    ----------
    rot_body_from_icrs : Rotation
    images : dict of str to ndarray
        Detector name (a head's name, or a split detector's) to its image (ADU, ``image[y, x]``).
    frames : dict of str to SimulatedImage or SplitFieldFrame
        The same with each detector's truth.
    blinded_by : dict of str to str
        Head name to the body that blinded it ("sun", "earth", "moon"), or "".
    """

    rot_body_from_icrs: Rotation
    images: dict[str, NDArray]
    frames: dict[str, SimulatedImage | SplitFieldFrame]
    blinded_by: dict[str, str]


def simulate_rig(rig: CameraRig, rot_body_from_icrs: Rotation, *, rate_body_rad_s: ArrayLike | None = None,
                 sensor: Sensor | dict[str, Sensor] | None = None, max_mag: float = DEFAULT_MAX_MAG,
                 epoch_jyear: float | None = None, rng: np.random.Generator | int | None = None,
                 noise: bool | NoiseModel = True, time: Time | None = None, bodies=None) -> RigFrame:
    """Render one scene through every detector of a rig (module docstring).

    Parameters
    ----------
    rig : CameraRig
    rot_body_from_icrs : Rotation
        Body attitude at mid-exposure.
    rate_body_rad_s : array_like, shape (3,), optional
        Body angular velocity, body frame, rad/s (not rendered on split detectors, see
        :mod:`._split_fov`).
    sensor : Sensor or dict of detector name to Sensor, optional
        Default :data:`startrack.simulate._scene.DEFAULT_SENSOR` for every detector.
    max_mag, epoch_jyear, noise
        As in :func:`startrack.simulate.simulate_frame`.
    rng : Generator, int or None
        Each detector draws from its own generator spawned from this one, in the rig's order.
    time : astropy.time.Time, optional
        Absolute time of mid-exposure (recorded in the truth of ordinary heads).
    bodies : BrightBodies, optional
        Sun, Earth and Moon for the exclusion test.

    Returns
    -------
    RigFrame
    """
    from ..multihead import blinded_by

    rate = np.zeros(3) if rate_body_rad_s is None else np.asarray(rate_body_rad_s, dtype=float)
    if rate.shape != (3,) or not np.all(np.isfinite(rate)):
        raise InvalidInputError(f"rate_body_rad_s must be 3 finite numbers (rad/s, body frame), "
                                f"got {rate_body_rad_s!r}")
    blinded = {h.name: blinded_by(h, bodies, h.rot_cam_from_icrs(rot_body_from_icrs).inv().apply([0, 0, 1.0]))
               for h in rig}
    detectors = rig.detectors
    streams = dict(zip(detectors, checked_rng(rng).spawn(len(detectors)), strict=True))
    frames: dict[str, SimulatedImage | SplitFieldFrame] = {}
    for name, heads in detectors.items():
        det_sensor = _sensor_for(sensor, name)
        stray = BLINDING_WELLS * det_sensor.detector.full_well_e if any(blinded[h.name] for h in heads) else 0.0
        if len(heads) > 1:
            frames[name] = simulate_split_frame(rig, name, rot_body_from_icrs, max_mag=max_mag, epoch_jyear=epoch_jyear,
                                                sensor=det_sensor, background_e=stray, rng=streams[name], noise=noise)
        else:
            frames[name] = _head_frame(heads[0], rot_body_from_icrs, rate, det_sensor, stray, max_mag,
                                       epoch_jyear, streams[name], noise, time)
    return RigFrame(rot_body_from_icrs, {k: f.image for k, f in frames.items()}, frames, blinded)


def _sensor_for(sensor: Sensor | dict[str, Sensor] | None, detector: str) -> Sensor:
    if isinstance(sensor, dict):
        if detector not in sensor:
            raise InvalidInputError(f"no sensor for detector {detector!r} (given for {', '.join(sensor)})")
        return sensor[detector]
    return DEFAULT_SENSOR if sensor is None else sensor


def _head_frame(head: RigHead, rot_body: Rotation, rate_body: NDArray, sensor: Sensor, stray_e: float,
                max_mag: float, epoch_jyear: float | None, rng: np.random.Generator, noise,
                time: Time | None) -> SimulatedImage:
    timing = FrameTiming(epoch=time) if time is not None else None
    return simulate_frame(head.camera, head.rot_cam_from_icrs(rot_body), max_mag=max_mag, epoch_jyear=epoch_jyear,
                          sensor=sensor, background_e=stray_e, rng=rng, noise=noise,
                          rate_rad_s=head.rot_cam_from_body.apply(rate_body), timing=timing)
