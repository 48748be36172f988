"""Catalog-driven frames: pick the Hipparcos stars in the field and render them.

A :class:`SkyModel` holds the stars down to a magnitude limit, as ICRS vectors at one epoch, with
a cone-search index (:class:`startrack.catalog.ConeIndex`); :func:`simulate_frame` searches a cone
around the boresight whose radius reaches the image corners plus the PSF stamp, and hands the
stars to :func:`startrack.simulate._scene.render_stars`, which projects them and keeps those that
light the detector. This is Huffman 2006's "catalog sequence" simulator for one frame (
Huffman 2006 Ch. 7 intro), with Hipparcos-2 in place of SKY2000.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..catalog import epoch_jyear as checked_jyear
from ..errors import InvalidInputError, check_instance, checked_rng
from ..frames import angle_between, boresight
from ._background import SkyBackground
from ._motion import AttitudeProfile
from ._noise import NoiseModel
from ._psf import DEFAULT_RADIUS_SIGMAS
from ._radiometry import Sensor
from ._rso import OrbitalScene, Snapshot
from ._scene import (
    FrameTiming,
    SimulatedImage,
    attitude_profile,
    checked_render_inputs,
    field_radius_rad,
    psf_radius_px,
    render_stars,
    star_arrays,
)
from ._streaks import Shutter

if TYPE_CHECKING:
    from ..catalog import ConeIndex, StarCatalog

DEFAULT_MAX_MAG: float = 6.0
"""Faintest V magnitude rendered by default (Huffman 2006 Table 7.1, "max M_V rendered")."""


@dataclass(frozen=True, eq=False)
class SkyModel:
    """Stars to render: ICRS unit vectors at one epoch, magnitudes and ids, with a cone index.

    Parameters
    ----------
    vectors_icrs : array_like, shape (N, 3)
        ICRS unit vectors of the stars.
    mags : array_like, shape (N,)
        Their magnitudes in the sensor's band (V for the default zero point).
    ids : array_like of int, shape (N,)
        Their identifiers (Hipparcos numbers).
    epoch_jyear : float or None
        Epoch of the positions (Julian year, TDB), recorded in the truth.
    b_v : array_like, shape (N,), optional
        Colours (NaN where unknown), for sensors with a passband.

    The arrays are stored as read-only copies (a cached model is shared); index them (which
    copies) before handing them to scipy's ``Rotation.apply``, which rejects read-only input.
    Build the Hipparcos one with :meth:`from_catalog`; :func:`simulate_frame` caches the default
    one per (max_mag, epoch).
    """

    vectors_icrs: NDArray[np.float64]
    mags: NDArray[np.float64]
    ids: NDArray[np.int64]
    epoch_jyear: float | None = None
    # None means unknown colours (NaN); __post_init__ fills it, so it is always an array once built.
    b_v: NDArray[np.float64] = None  # type: ignore[assignment]
    index: ConeIndex = field(init=False, repr=False)

    def __post_init__(self) -> None:
        from ..catalog import ConeIndex

        vectors, mags, ids = star_arrays(self.vectors_icrs, self.mags, self.ids)
        b_v = np.full(len(ids), np.nan) if self.b_v is None else np.asarray(self.b_v, dtype=float)
        if b_v.shape != ids.shape:
            raise InvalidInputError(f"b_v must have shape {ids.shape}, got {b_v.shape}")
        for name, value in (("vectors_icrs", vectors), ("mags", mags), ("ids", ids), ("b_v", b_v)):
            value = value.copy()  # read-only copies: the caller's arrays stay writable
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        object.__setattr__(self, "index", ConeIndex(vectors) if len(ids) else None)

    @classmethod
    def from_catalog(cls, catalog: StarCatalog | None = None, *, max_mag: float = DEFAULT_MAX_MAG,
                     epoch_jyear: float | Time | None = None, band: str = "v") -> SkyModel:
        """The stars of ``catalog`` (Hipparcos-2 when None) with magnitude <= ``max_mag``.

        ``band`` is "v" (Johnson V, matching the default zero point) or "hp" (Hipparcos Hp);
        positions are propagated to ``epoch_jyear`` (None: the catalog's epoch).
        """
        from ..catalog import load_catalog

        if band not in ("v", "hp"):
            raise InvalidInputError(f"band must be 'v' or 'hp', got {band!r}")
        cat = load_catalog() if catalog is None else catalog
        subset = cat.brighter_than(_max_mag(max_mag), band=band)
        mags = np.asarray(subset.v_mag if band == "v" else subset.hp_mag, dtype=float)
        keep = np.isfinite(mags)
        epoch = None if epoch_jyear is None else checked_jyear(epoch_jyear, "epoch_jyear")
        return cls(vectors_icrs=np.asarray(subset.vectors(epoch), dtype=float)[keep],
                   mags=mags[keep], ids=np.asarray(subset.hip)[keep],
                   b_v=np.asarray(subset.b_v, dtype=float)[keep],
                   epoch_jyear=getattr(cat, "epoch_jyear", None) if epoch is None else epoch)

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def with_false_stars(self, count: int, rng: np.random.Generator | int | None = None,
                         mag_range: tuple[float, float] = (2.0, 6.0)) -> SkyModel:
        """This sky plus ``count`` point sources that no catalog holds, uniform over the sphere.

        They stand for Jacobs 1995's false stars (§7.4: novae, variables far from their catalog
        magnitude, planets) and for debris: identification must survive them. Their ids are
        -1, -2, ... (negative: never a HIP number), their magnitudes uniform in ``mag_range``.
        """
        if not (isinstance(count, int | np.integer) and count >= 0):
            raise InvalidInputError(f"count must be a whole number >= 0, got {count!r}")
        lo, hi = (float(v) for v in mag_range)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise InvalidInputError(f"mag_range must be (faint >= bright) finite magnitudes, got {mag_range!r}")
        rng = checked_rng(rng)
        vectors = rng.standard_normal((count, 3))
        vectors /= np.linalg.norm(vectors, axis=1, keepdims=True)
        return SkyModel(vectors_icrs=np.concatenate([self.vectors_icrs, vectors]),
                        mags=np.concatenate([self.mags, rng.uniform(lo, hi, count)]),
                        ids=np.concatenate([self.ids, -1 - np.arange(count, dtype=np.int64)]),
                        epoch_jyear=self.epoch_jyear, b_v=np.concatenate([self.b_v, np.full(count, np.nan)]))

    def cone(self, center_icrs: NDArray[np.float64], radius_rad: float) -> NDArray[np.intp]:
        """Indices of the stars within ``radius_rad`` of the unit vector ``center_icrs``."""
        if self.index is None:
            return np.zeros(0, dtype=np.intp)
        return np.asarray(self.index.query(np.asarray(center_icrs, dtype=float), float(radius_rad)),
                          dtype=np.intp)


def _max_mag(max_mag: float) -> float:
    """``max_mag`` as a finite float, else InvalidInputError."""
    try:
        value = float(max_mag)
    except (TypeError, ValueError):
        value = float("nan")
    if not np.isfinite(value):
        raise InvalidInputError(f"max_mag must be a finite magnitude, got {max_mag!r}")
    return value


@functools.lru_cache(maxsize=8)
def _default_sky(max_mag: float, epoch_jyear: float | None, band: str) -> SkyModel:
    return SkyModel.from_catalog(max_mag=max_mag, epoch_jyear=epoch_jyear, band=band)


def simulate_frame(camera: Camera, rot_cam_from_icrs: Rotation | AttitudeProfile, *,
                   max_mag: float = DEFAULT_MAX_MAG, epoch_jyear: float | Time | None = None,
                   sensor: Sensor | None = None, background_e: float = 0.0,
                   rng: np.random.Generator | int | None = None, noise: bool | NoiseModel = True,
                   sky: SkyModel | None = None, radius_sigmas: float = DEFAULT_RADIUS_SIGMAS,
                   rate_rad_s: ArrayLike | None = None, timing: FrameTiming | None = None,
                   sky_background: SkyBackground | None = None,
                   orbital: OrbitalScene | Snapshot | None = None) -> SimulatedImage:
    """Render the Hipparcos sky seen by ``camera`` at an attitude or over an attitude profile.

    Parameters
    ----------
    camera : Camera
    rot_cam_from_icrs : Rotation or attitude profile
        A single attitude at the frame's mid time (maps ICRS vectors into the camera frame), or a
        profile from :mod:`startrack.simulate._motion`.
    max_mag : float
        Faintest V magnitude rendered.
    epoch_jyear : float, astropy Time or None
        Epoch the catalog positions are propagated to (Julian year, TDB); None keeps the catalog
        epoch (1991.25 for Hipparcos). Ignored when ``sky`` is given (its epoch is used).
    sensor : Sensor, optional
        The Huffman 2006 FAR-MST sensor when None.
    background_e, rng, noise, radius_sigmas, rate_rad_s, timing, sky_background, orbital
        As in :func:`startrack.simulate._scene.render_stars`.
    sky : SkyModel, optional
        Preloaded stars (e.g. another catalog or magnitude band); stars fainter than ``max_mag``
        are still left out. When None, Hipparcos-2 is loaded and indexed once per
        (max_mag, epoch) and kept in memory.

    Returns
    -------
    SimulatedImage
        Image in ADU and its truth (HIP numbers, true pixel positions, brightest first).
    """
    sensor, frame_timing, radius_sigmas = checked_render_inputs(camera, sensor, timing, radius_sigmas)
    if sky is None:
        epoch = None if epoch_jyear is None else checked_jyear(epoch_jyear, "epoch_jyear")
        sky = _default_sky(_max_mag(max_mag), epoch, "v")
    check_instance(sky, SkyModel, "sky")
    profile, moving = attitude_profile(rot_cam_from_icrs, rate_rad_s)
    shutter = frame_timing.shutter(sensor.exposure_s, camera.height)
    centre, extra = _swept_cone(profile, shutter, camera.height, moving)
    margin = float(psf_radius_px(camera, sensor, radius_sigmas))
    idx = sky.cone(centre, field_radius_rad(camera, margin) + extra)
    idx = idx[sky.mags[idx] <= max_mag]
    return render_stars(camera, rot_cam_from_icrs, sky.vectors_icrs[idx], sky.mags[idx], sky.ids[idx],
                        sensor=sensor, background_e=background_e, rng=rng, noise=noise,
                        radius_sigmas=radius_sigmas, epoch_jyear=sky.epoch_jyear, b_v=sky.b_v[idx],
                        rate_rad_s=rate_rad_s, timing=timing, sky_background=sky_background, orbital=orbital)


def _swept_cone(profile: AttitudeProfile, shutter: Shutter, height: int, moving: bool
                ) -> tuple[NDArray[np.float64], float]:
    """Boresight at the frame's mid time and the largest angle it moves from there during the
    frame (sampled at 17 times, plus 1 % and one sample step for safety)."""
    mid = boresight(profile.attitudes([shutter.mid_s(height)])[0])
    if not moving:
        return mid, 0.0
    span_end = shutter.start_s + shutter.exposure_s + (height - 1) * shutter.line_time_s
    axes = boresight(profile.attitudes(np.linspace(shutter.start_s, span_end, 17)))
    swept = angle_between(axes, mid[None, :])
    step = float(np.max(angle_between(axes[1:], axes[:-1])))
    return mid, 1.01 * float(swept.max()) + step
