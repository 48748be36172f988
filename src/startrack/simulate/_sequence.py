"""Sequences of frames over an attitude profile, streamed one frame at a time.

Frame k is exposed from ``start_s + k / frame_rate_hz`` for the sensor's exposure time, on the
profile's clock (:mod:`._motion`: inertial hold, constant-rate slew, tumble about any axis, a
recorded profile from a file). Each frame's noise comes from its own generator,
``default_rng(SeedSequence(seed, spawn_key=(k,)))``, so frame k is the same whether it is
rendered alone or in a sequence, and the frames are independent. Satellite geometry (orbits, Sun,
Moon) is computed for blocks of frames at once. This is Huffman 2006's "catalog sequence" (
Huffman 2006 Ch. 7 intro) with the truth of every frame.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator

import numpy as np
from astropy.time import Time, TimeDelta

from ..camera import Camera
from ..errors import InvalidInputError
from . import _checks
from ._background import SkyBackground
from ._motion import AttitudeProfile
from ._noise import NoiseModel
from ._psf import DEFAULT_RADIUS_SIGMAS
from ._radiometry import Sensor
from ._rso import OrbitalScene
from ._scene import DEFAULT_SENSOR, DEFAULT_SUBSTEP_PX, FrameTiming
from ._sky import DEFAULT_MAX_MAG, SkyModel, simulate_frame
from ._truth import SimulatedImage

SNAPSHOT_BLOCK = 256
"""Frames whose satellite geometry is computed together."""


def frame_rng(seed: int, index: int) -> np.random.Generator:
    """The noise generator of frame ``index`` of a sequence seeded with ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index,)))


def simulate_sequence(camera: Camera, profile: AttitudeProfile, n_frames: int, *, frame_rate_hz: float,
                      start_s: float = 0.0, epoch: Time | None = None, sensor: Sensor | None = None,
                      max_mag: float = DEFAULT_MAX_MAG, catalog_epoch_jyear: float | None = None,
                      seed: int | None = None, noise: bool | NoiseModel = True, sky: SkyModel | None = None,
                      sky_background: SkyBackground | None = None, orbital: OrbitalScene | None = None,
                      line_time_s: float = 0.0, substep_px: float = DEFAULT_SUBSTEP_PX,
                      radius_sigmas: float = DEFAULT_RADIUS_SIGMAS,
                      progress: Callable[[int, int], None] | None = None) -> Iterator[SimulatedImage]:
    """Yield ``n_frames`` simulated frames of ``profile``, each with its truth.

    Parameters
    ----------
    camera : Camera
    profile : attitude profile
        From :mod:`startrack.simulate._motion` (or anything with ``attitudes`` and ``rates``).
    n_frames : int
    frame_rate_hz : float
        Frames per second; the exposure must fit in one frame period.
    start_s : float
        Start of frame 0 on the profile's clock (s).
    epoch : astropy.time.Time, optional
        Absolute time of the profile's t = 0 (needed for satellites; sets the frames' time tags).
    sensor, max_mag, noise, sky, sky_background, line_time_s, substep_px, radius_sigmas
        As in :func:`startrack.simulate._sky.simulate_frame`.
    catalog_epoch_jyear : float, optional
        Epoch of the star positions (Julian year).
    seed : int, optional
        Seed of the noise of every frame (see :func:`frame_rng`); None draws a fresh one.
    orbital : OrbitalScene, optional
    progress : callable(done, total), optional
        Called after each frame.

    Yields
    ------
    SimulatedImage
        With ``truth.frame_index`` = k and the truth at the frame's mid time.
    """
    sensor = DEFAULT_SENSOR if sensor is None else sensor
    n = _frame_count(n_frames)
    period = 1.0 / _checks.positive("frame_rate_hz", frame_rate_hz)
    if sensor.exposure_s + (camera.height - 1) * line_time_s > period * (1 + 1e-9):
        raise InvalidInputError(f"the exposure ({sensor.exposure_s:g} s plus the rolling-shutter read-out) "
                                f"does not fit in a frame period of {period:g} s")
    if orbital is not None and epoch is None:
        raise InvalidInputError("satellites need epoch=Time(...) (the absolute time of t = 0)")
    if seed is None:
        seed = int(np.random.default_rng().integers(2**63))  # fresh OS entropy
    starts = float(start_s) + period * np.arange(n)
    mids = starts + 0.5 * sensor.exposure_s + 0.5 * (camera.height - 1) * line_time_s
    snapshots: list = []
    for k in range(n):
        if orbital is not None and k % SNAPSHOT_BLOCK == 0:
            snapshots = orbital.snapshots(epoch + TimeDelta(mids[k:k + SNAPSHOT_BLOCK], format="sec"))
        timing = FrameTiming(start_s=float(starts[k]), line_time_s=line_time_s, substep_px=substep_px,
                             epoch=epoch)
        sim = simulate_frame(camera, profile, max_mag=max_mag, epoch_jyear=catalog_epoch_jyear, sensor=sensor,
                             rng=frame_rng(seed, k), noise=noise, sky=sky, radius_sigmas=radius_sigmas,
                             timing=timing, sky_background=sky_background,
                             orbital=snapshots[k % SNAPSHOT_BLOCK] if orbital is not None else None)
        yield SimulatedImage(sim.image, dataclasses.replace(sim.truth, frame_index=k))
        if progress is not None:
            progress(k + 1, n)


def _frame_count(n_frames: int) -> int:
    if not (isinstance(n_frames, int | np.integer) and n_frames >= 1):
        raise InvalidInputError(f"n_frames must be a whole number >= 1, got {n_frames!r}")
    return int(n_frames)
