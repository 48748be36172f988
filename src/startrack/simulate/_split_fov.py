"""Split-field-of-view frames: two fields of the sky superimposed on one detector, each with its own
astigmatic PSF (Samaan 2002 Eq. 4–5, StarNav II).

Each field is a head of a :class:`startrack.CameraRig` that names the shared ``detector`` and has a
:class:`startrack.rig.PsfShape`: an elliptical Gaussian with its own sigmas and direction
(deliberate astigmatism: in the seed's Fig. 4 the left field's stars are stretched vertically and
the right field's horizontally). The stars of every field are projected through that field's
camera model and mounting, drawn with its PSF (pixel-integrated by the midpoint rule on
``oversample^2`` sub-pixels: an elliptical Gaussian at an angle is not separable), added into one
signal image, and read out once with the sensor's noise. The truth says which field every star
came from.

Smear is not rendered: the seed notes that astigmatic tagging restricts the rate to the
negligible-smear regime (smear elongates spots too), so split frames are still frames.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..rig import CameraRig, PsfShape, RigHead
from ._noise import NoiseModel, read_out
from ._psf import DEFAULT_RADIUS_SIGMAS, add_stamps, stamp_radius_px
from ._radiometry import Sensor
from ._scene import DEFAULT_SENSOR, field_radius_rad, project_stars
from ._sky import DEFAULT_MAX_MAG, SkyModel, _default_sky

OVERSAMPLE = 4
"""Sub-pixels per axis of the midpoint-rule PSF integration."""


def elliptical_stamps(x: NDArray, y: NDArray, flux: NDArray, psf: PsfShape, oversample: int = OVERSAMPLE,
                      radius_sigmas: float = DEFAULT_RADIUS_SIGMAS
                      ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """Pixel-integrated elliptical Gaussian stamps of N sources (the form of
    :func:`startrack.simulate._psf.gaussian_stamps`): central pixels x0, y0 (N,) and stamps (N, S, S)
    with ``stamps[n, j, i]`` the light of source n in pixel (x0 + i - R, y0 + j - R)."""
    radius = stamp_radius_px(psf.sigma_major_px, radius_sigmas)
    x0, y0 = np.floor(x + 0.5).astype(np.intp), np.floor(y + 0.5).astype(np.intp)
    sub = (np.arange(oversample) + 0.5) / oversample - 0.5
    grid = (np.arange(-radius, radius + 1)[:, None] + sub[None, :]).ravel()  # (S * os,)
    dx = grid[None, None, :] - (x - x0)[:, None, None]
    dy = grid[None, :, None] - (y - y0)[:, None, None]
    angle = math.radians(psf.angle_deg)
    c, s = math.cos(angle), math.sin(angle)
    along, across = dx * c + dy * s, -dx * s + dy * c
    density = np.exp(-0.5 * ((along / psf.sigma_major_px) ** 2 + (across / psf.sigma_minor_px) ** 2))
    density *= 1.0 / (2.0 * math.pi * psf.sigma_major_px * psf.sigma_minor_px * oversample**2)
    size = 2 * radius + 1
    stamps = density.reshape(len(x), size, oversample, size, oversample).sum(axis=(2, 4))
    return x0, y0, stamps * flux[:, None, None]


@dataclass(frozen=True)
class SplitFieldTruth:
    """What a split-FOV frame contains, brightest star first.

    Attributes
    ----------
    detector : str
    rot_body_from_icrs : Rotation
    rot_cam_from_icrs : dict of str to Rotation
        Each field's attitude.
    field : ndarray of str, shape (K,)
        The field (head name) each star came from.
    ids, x, y, mag, electrons : ndarray, shape (K,)
        HIP number, true position (px), V magnitude and expected electrons of each star whose
        stamp reaches the detector.
    sensor : Sensor
    noise : NoiseModel
    """

    detector: str
    rot_body_from_icrs: Rotation
    rot_cam_from_icrs: dict[str, Rotation]
    field: NDArray[np.str_]
    ids: NDArray[np.int64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    mag: NDArray[np.float64]
    electrons: NDArray[np.float64]
    sensor: Sensor
    noise: NoiseModel

    def __len__(self) -> int:
        return int(self.ids.size)


@dataclass(frozen=True)
class SplitFieldFrame:
    """A split-FOV image (ADU, ``image[y, x]``) and its truth."""

    image: NDArray
    truth: SplitFieldTruth


def _field_stars(head: RigHead, rot_cam: Rotation, sky: SkyModel, sensor: Sensor, max_mag: float):
    """(x, y, ids, mags, electrons) of the stars of one field whose stamp reaches the detector."""
    radius = stamp_radius_px(head.field_psf.sigma_major_px)
    boresight = rot_cam.inv().apply([0.0, 0.0, 1.0])
    idx = sky.cone(boresight, field_radius_rad(head.camera, radius))
    idx = idx[sky.mags[idx] <= max_mag]
    x, y, visible = project_stars(head.camera, rot_cam, sky.vectors_icrs[idx], margin_px=radius)
    idx = idx[visible]
    electrons = sensor.electrons(sky.mags[idx], sky.b_v[idx])
    return x[visible], y[visible], sky.ids[idx], sky.mags[idx], electrons


def simulate_split_frame(rig: CameraRig, detector: str, rot_body_from_icrs: Rotation, *,
                         max_mag: float = DEFAULT_MAX_MAG, epoch_jyear: float | None = None,
                         sensor: Sensor | None = None, background_e: float = 0.0,
                         rng: np.random.Generator | int | None = None, noise: bool | NoiseModel = True,
                         sky: SkyModel | None = None) -> SplitFieldFrame:
    """Render the fields of a split detector of ``rig`` at a body attitude (module docstring).

    Parameters
    ----------
    rig : CameraRig
    detector : str
        A detector shared by two or more heads of the rig (:meth:`CameraRig.split_detectors`).
    rot_body_from_icrs : Rotation
        The body attitude; each field's is its mounting times this.
    max_mag, epoch_jyear, sensor, background_e, rng, noise, sky
        As in :func:`startrack.simulate.simulate_frame` (the sensor's own PSF width is not used:
        each field has its :class:`~startrack.rig.PsfShape`).

    Returns
    -------
    SplitFieldFrame
    """
    fields = rig.split_detectors().get(detector)
    if fields is None:
        raise InvalidInputError(f"{detector!r} is not a detector shared by several heads of the rig "
                                f"(split detectors: {', '.join(rig.split_detectors()) or 'none'})")
    sensor = DEFAULT_SENSOR if sensor is None else sensor
    sky = _default_sky(float(max_mag), epoch_jyear, "v") if sky is None else sky
    camera = fields[0].camera
    signal = np.zeros((camera.height, camera.width))
    parts = []
    for head in fields:
        rot_cam = head.rot_cam_from_icrs(rot_body_from_icrs)
        x, y, ids, mags, electrons = _field_stars(head, rot_cam, sky, sensor, max_mag)
        if len(ids):
            add_stamps(signal, *elliptical_stamps(x, y, electrons, head.field_psf))
        parts.append((np.full(len(ids), head.name), ids, x, y, mags, electrons))
    model = NoiseModel.coerce(noise)
    image = read_out(signal, sensor, background_e=background_e, noise=model, rng=rng)
    field, ids, x, y, mags, electrons = (np.concatenate(p) for p in zip(*parts, strict=True))
    order = np.argsort(mags, kind="stable")
    truth = SplitFieldTruth(detector, rot_body_from_icrs, {h.name: h.rot_cam_from_icrs(rot_body_from_icrs)
                                                           for h in fields},
                            field[order], ids[order].astype(np.int64), x[order], y[order], mags[order],
                            electrons[order], sensor, model)
    return SplitFieldFrame(image, truth)
