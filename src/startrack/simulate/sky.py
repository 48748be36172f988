"""Catalog-driven frames: pick the Hipparcos stars in the field and render them.

A :class:`SkyModel` holds the stars down to a magnitude limit, as ICRS vectors at one epoch, with
a cone-search index (:class:`startrack.catalog.ConeIndex`); :func:`simulate_frame` searches a cone
around the boresight whose radius reaches the image corners plus the PSF stamp, and hands the
stars to :func:`startrack.simulate.scene.render_stars`, which projects them and keeps those that
light the detector. This is seed 000's "catalog sequence" simulator for one frame (notes
``seed-000.md`` §1.4), with Hipparcos-2 in place of SKY2000.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError
from ..frames import boresight
from .noise import NoiseModel
from .psf import DEFAULT_RADIUS_SIGMAS, stamp_radius_px
from .radiometry import Sensor
from .scene import DEFAULT_SENSOR, SimulatedImage, field_radius_rad, render_stars, star_arrays

if TYPE_CHECKING:
    from ..catalog import ConeIndex, StarCatalog

DEFAULT_MAX_MAG: float = 6.0
"""Faintest V magnitude rendered by default (seed 000 Table 7.1, "max M_V rendered")."""


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

    The arrays are stored as read-only copies (a cached model is shared); index them (which
    copies) before handing them to scipy's ``Rotation.apply``, which rejects read-only input.
    Build the Hipparcos one with :meth:`from_catalog`; :func:`simulate_frame` caches the default
    one per (max_mag, epoch).
    """

    vectors_icrs: NDArray[np.float64]
    mags: NDArray[np.float64]
    ids: NDArray[np.int64]
    epoch_jyear: float | None = None
    index: ConeIndex = field(init=False, repr=False)

    def __post_init__(self) -> None:
        from ..catalog import ConeIndex

        vectors, mags, ids = star_arrays(self.vectors_icrs, self.mags, self.ids)
        for name, value in (("vectors_icrs", vectors), ("mags", mags), ("ids", ids)):
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
        epoch = None if epoch_jyear is None else _as_jyear(epoch_jyear)
        return cls(vectors_icrs=np.asarray(subset.vectors(epoch), dtype=float)[keep],
                   mags=mags[keep], ids=np.asarray(subset.hip)[keep],
                   epoch_jyear=getattr(cat, "epoch_jyear", None) if epoch is None else epoch)

    def __len__(self) -> int:
        return int(self.ids.shape[0])

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


def _as_jyear(epoch: float | Time) -> float:
    if isinstance(epoch, Time):
        return float(epoch.tdb.jyear)
    return float(epoch)


@functools.lru_cache(maxsize=8)
def _default_sky(max_mag: float, epoch_jyear: float | None, band: str) -> SkyModel:
    return SkyModel.from_catalog(max_mag=max_mag, epoch_jyear=epoch_jyear, band=band)


def simulate_frame(camera: Camera, rot_cam_from_icrs: Rotation, *, max_mag: float = DEFAULT_MAX_MAG,
                   epoch_jyear: float | Time | None = None, sensor: Sensor | None = None,
                   background_e: float = 0.0, rng: np.random.Generator | int | None = None,
                   noise: bool | NoiseModel = True, sky: SkyModel | None = None,
                   radius_sigmas: float = DEFAULT_RADIUS_SIGMAS) -> SimulatedImage:
    """Render the Hipparcos sky seen by ``camera`` at attitude ``rot_cam_from_icrs``.

    Parameters
    ----------
    camera : Camera
    rot_cam_from_icrs : Rotation
        Single attitude; maps ICRS vectors into the camera frame.
    max_mag : float
        Faintest V magnitude rendered.
    epoch_jyear : float, astropy Time or None
        Epoch the catalog positions are propagated to (Julian year, TDB); None keeps the catalog
        epoch (1991.25 for Hipparcos). Ignored when ``sky`` is given (its epoch is used).
    sensor : Sensor, optional
        The seed 000 FAR-MST sensor when None.
    background_e, rng, noise, radius_sigmas
        As in :func:`startrack.simulate.scene.render_stars`.
    sky : SkyModel, optional
        Preloaded stars (e.g. another catalog or magnitude band); stars fainter than ``max_mag``
        are still left out. When None, Hipparcos-2 is loaded and indexed once per
        (max_mag, epoch) and kept in memory.

    Returns
    -------
    SimulatedImage
        Image in ADU and its truth (HIP numbers, true pixel positions, brightest first).
    """
    sensor = DEFAULT_SENSOR if sensor is None else sensor
    if sky is None:
        epoch = None if epoch_jyear is None else _as_jyear(epoch_jyear)
        sky = _default_sky(_max_mag(max_mag), epoch, "v")
    margin = float(stamp_radius_px(sensor.psf_sigma_px, radius_sigmas))
    idx = sky.cone(boresight(rot_cam_from_icrs), field_radius_rad(camera, margin))
    idx = idx[sky.mags[idx] <= max_mag]
    return render_stars(camera, rot_cam_from_icrs, sky.vectors_icrs[idx], sky.mags[idx],
                        sky.ids[idx], sensor=sensor, background_e=background_e, rng=rng,
                        noise=noise, radius_sigmas=radius_sigmas, epoch_jyear=sky.epoch_jyear)
