"""startrack in the loop: star images simulated from the true attitude and rate, detected and
followed by the :class:`startrack.track.Tracker`, as the controller's attitude and rate.

Timing of frame k (``StarTrackerSetup``): the exposure runs from ``k / f`` for ``exposure_s``; the
image is rendered by :func:`startrack.simulate.simulate_frame` from the true attitude and body
rate at mid-exposure (the smear of a constant rate over the exposure; the acceleration over one
exposure, < 0.004 rad/s at the coil's limit, is left out). The tracker's attitude is valid at
mid-exposure; its rate is an exponentially smoothed difference of attitudes (gain g), which for a
steadily changing rate lags the attitude by ``dt / 2 + dt (1 - g) / g`` (dt since the previous
tracked frame): that is the rate's time tag. The result is available at the end of the exposure
plus the processing time (detection + tracking), measured on this machine for every frame unless
``latency_s`` fixes it; one processor handles the frames in order, so a frame waits while the
previous one is still being processed. The controller propagates the newest result to the
present (:mod:`._estimate`).

Frames: the camera is fixed to the body (``rot_cam_from_body``, identity by default: boresight
body +z, so the turn about y sweeps the stars along image x); the reference frame is fixed in
ICRS (``rot_ref_from_icrs``), so ``rot_cam_from_icrs = rot_cam_from_body rot_body_from_ref
rot_ref_from_icrs`` and the camera-frame rate is ``rot_cam_from_body`` applied to the body rate.

:class:`ModelTrackerFeedback` replaces the images by the truth plus Gaussian errors whose sizes,
latency and validity were fitted from a tracker run (:func:`fit_noise_model`), for long runs.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..detect import StarDetector
from ..errors import InvalidInputError, check_int, checked_count, checked_number
from ..frames import rotation_from_radec_roll
from ..simulate import Sensor, frame_rng, get_sensor_preset, simulate_frame
from ..track import Tracker, TrackerOptions
from ._estimate import CommandLog, Estimate, Measurement, estimate_from, y_angle


def _default_camera() -> Camera:
    return Camera.from_fov(256, 256, 20.0)


def _default_sensor() -> Sensor:
    return get_sensor_preset("generic-cmos").with_exposure(0.1)


def _default_reference() -> Rotation:
    """The reference frame's axes in ICRS: at theta = 0 the boresight looks at RA 100, Dec +20 deg."""
    return rotation_from_radec_roll(math.radians(100.0), math.radians(20.0), 0.0)


@dataclass(frozen=True)
class StarTrackerSetup:
    """Camera, sensor, frame rate and mounting of the star tracker in the loop.

    Parameters
    ----------
    camera : Camera
        Default 256 x 256 px, 20 deg (281 arcsec/px): small images keep a 700 s run at 5 Hz to
        about a minute, and 20 deg hold tens of stars to V 7.5 anywhere on the sky.
    sensor : Sensor
        Default the generic CMOS preset with a 0.1 s exposure.
    frame_rate_hz : float
        Frames per second (the issue asks for 2-10 Hz); the exposure must fit in a period.
    max_mag : float
        Faintest star rendered (V).
    rot_cam_from_body, rot_ref_from_icrs : Rotation
        Mounting and the reference frame's orientation (see the module docstring).
    latency_s : float or None
        Processing time added after the exposure; None uses the measured time of each frame.
    seed : int
        Seed of the image noise (frame k uses ``frame_rng(seed, k)``).
    tracker_options : TrackerOptions
    """

    camera: Camera = field(default_factory=_default_camera)
    sensor: Sensor = field(default_factory=_default_sensor)
    frame_rate_hz: float = 5.0
    max_mag: float = 7.5
    rot_cam_from_body: Rotation = field(default_factory=Rotation.identity)
    rot_ref_from_icrs: Rotation = field(default_factory=_default_reference)
    latency_s: float | None = None
    seed: int = 0
    tracker_options: TrackerOptions = field(default_factory=TrackerOptions)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.frame_rate_hz) and self.frame_rate_hz > 0):
            raise InvalidInputError(f"frame_rate_hz must be positive, got {self.frame_rate_hz!r}")
        if self.sensor.exposure_s > 1.0 / self.frame_rate_hz:
            raise InvalidInputError(f"the exposure ({self.sensor.exposure_s:g} s) does not fit in a frame period "
                                    f"of {1 / self.frame_rate_hz:g} s; lower frame_rate_hz")
        check_int(self, ("seed",), 0)
        if self.latency_s is not None and not (math.isfinite(self.latency_s) and 0 <= self.latency_s <= MAX_LATENCY_S):
            raise InvalidInputError(f"latency_s must be None or 0 to {MAX_LATENCY_S:g} s, got {self.latency_s!r} (the "
                                    "noise model fitted from the run holds latencies to a minute)")

    @property
    def exposure_s(self) -> float:
        return self.sensor.exposure_s

    def mid_times(self, t0_s: float, t1_s: float) -> list[tuple[int, float]]:
        """(frame index, mid-exposure time) of the frames whose mid time is in [t0_s, t1_s)."""
        half, rate = 0.5 * self.exposure_s, self.frame_rate_hz
        first, last = math.ceil((t0_s - half) * rate - 1e-9), math.ceil((t1_s - half) * rate - 1e-9)
        return [(k, k / rate + half) for k in range(max(first, 0), last)]

    def rot_cam_from_icrs(self, rot_ref_from_body: Rotation) -> Rotation:
        return self.rot_cam_from_body * rot_ref_from_body.inv() * self.rot_ref_from_icrs

    def rot_ref_from_body(self, rot_cam_from_icrs: Rotation) -> Rotation:
        return (self.rot_cam_from_body.inv() * rot_cam_from_icrs * self.rot_ref_from_icrs.inv()).inv()


@dataclass(frozen=True)
class FrameRecord:
    """What one frame gave: times (s), the tracker's verdict, the wall time of rendering the image
    (the simulated world, not part of the latency) and of processing it (detection + tracking, s),
    and its y angle and rate against the truth."""

    index: int
    t_mid_s: float
    t_available_s: float
    t_rate_s: float
    ok: bool
    mode: str
    reason: str
    n_matched: int
    processing_s: float
    render_s: float
    theta_true_rad: float
    theta_est_rad: float
    omega_est_rad_s: float

    @property
    def latency_s(self) -> float:
        """From mid-exposure to the result, s."""
        return self.t_available_s - self.t_mid_s


class _FramedFeedback:
    """Frames at the setup's rate; measurements queued until available, the newest one used."""

    name = "framed"

    def __init__(self, setup: StarTrackerSetup, log: CommandLog):
        self.setup, self.log = setup, log
        self.frames: list[FrameRecord] = []
        self._pending: list[Measurement] = []
        self._latest: Measurement | None = None
        self._last_ok_t: float | None = None
        self._busy_until = -math.inf

    def sample_times(self, t0_s: float, t1_s: float) -> list[float]:
        return [t for _, t in self.setup.mid_times(t0_s, t1_s)]

    def observe(self, t_s: float, rot_ref_from_body: Rotation, rate_body_rad_s: NDArray) -> None:
        k = round((t_s - 0.5 * self.setup.exposure_s) * self.setup.frame_rate_hz)
        measurement, record = self._measure(k, t_s, rot_ref_from_body, np.asarray(rate_body_rad_s, dtype=float))
        self.frames.append(record)
        if measurement is not None:
            self._pending.append(measurement)
            self._last_ok_t = t_s

    def estimate(self, t_s: float, plant, log: CommandLog) -> Estimate:
        while self._pending and self._pending[0].t_available_s <= t_s:
            self._latest = self._pending.pop(0)
        return estimate_from(self.log, self._latest, t_s)

    def _available(self, t_mid_s: float, processing_s: float) -> float:
        """When frame results are ready: processing starts at the end of the exposure, or when the
        previous frame's is done (one processor, frames in order)."""
        latency = processing_s if self.setup.latency_s is None else self.setup.latency_s
        self._busy_until = max(t_mid_s + 0.5 * self.setup.exposure_s, self._busy_until) + latency
        return self._busy_until

    def _fallback_rate(self, t_s: float) -> NDArray[np.float64]:
        """The rate of the previous measurement carried to ``t_s`` (zero without one)."""
        if self._latest is None:
            return np.zeros(3)
        return self.log.propagate(self._latest, t_s)[1]

    def _measure(self, k: int, t_s: float, rot: Rotation, rate: NDArray) -> tuple[Measurement | None, FrameRecord]:
        raise NotImplementedError


class StarTrackerFeedback(_FramedFeedback):
    """The full pipeline: simulate the frame, detect its stars, :meth:`Tracker.update`."""

    name = "tracker"

    def __init__(self, setup: StarTrackerSetup, log: CommandLog, warm_up: bool = True):
        super().__init__(setup, log)
        self.tracker = Tracker(camera=setup.camera, options=setup.tracker_options)
        self.detector = StarDetector()
        self.warm_up_s = self._warm_up() if warm_up else 0.0

    def _warm_up(self) -> float:
        """Solve one frame at the reference attitude and forget it: loads the catalog, the pattern
        database and the compiled kernels before the run (a one-time start-up, not a per-frame
        latency). Returns its wall time, s."""
        start = time.perf_counter()
        setup = self.setup
        sim = simulate_frame(setup.camera, setup.rot_cam_from_icrs(Rotation.identity()), sensor=setup.sensor,
                             max_mag=setup.max_mag, rng=np.random.default_rng([setup.seed, 7]))
        self.tracker.update_image(sim.image, -1.0, detector=self.detector)
        self.tracker.reset()
        return time.perf_counter() - start

    def _measure(self, k: int, t_s: float, rot: Rotation, rate: NDArray) -> tuple[Measurement | None, FrameRecord]:
        setup = self.setup
        start = time.perf_counter()
        sim = simulate_frame(setup.camera, setup.rot_cam_from_icrs(rot), sensor=setup.sensor, max_mag=setup.max_mag,
                             rate_rad_s=setup.rot_cam_from_body.apply(rate), rng=frame_rng(setup.seed, k))
        render = time.perf_counter() - start
        start = time.perf_counter()
        step = self.tracker.update_image(sim.image, t_s, detector=self.detector)
        processing = time.perf_counter() - start
        available = self._available(t_s, processing)
        ok = step.rot_cam_from_icrs is not None
        est_rot = setup.rot_ref_from_body(step.rot_cam_from_icrs) if ok else None
        t_rate, est_rate = self._rate(step.rate_rad_s, t_s)
        record = FrameRecord(k, t_s, available, t_rate, ok, step.mode, step.reason, step.n_matched, processing,
                             render, y_angle(rot), y_angle(est_rot) if ok else math.nan,
                             float(est_rate[1]) if ok else math.nan)
        if not ok:
            return None, record
        return Measurement(t_s, t_rate, available, est_rot, est_rate), record

    def _rate(self, rate_cam: NDArray | None, t_s: float) -> tuple[float, NDArray[np.float64]]:
        """The body rate and its time tag (see the module docstring); the previous one when the tracker has none."""
        if rate_cam is None or self._last_ok_t is None:
            return t_s, self._fallback_rate(t_s)
        gain = self.setup.tracker_options.rate_gain
        step = t_s - self._last_ok_t
        return t_s - step * (0.5 + (1.0 - gain) / gain), self.setup.rot_cam_from_body.inv().apply(rate_cam)


MAX_LATENCY_S = 30.0
"""The longest fixed processing latency a tracker setup takes, s: with up to half an exposure (a
frame period, itself under 60 s) added, the noise model's latency stays within its minute."""

NOISE_MODEL_RANGES: tuple[tuple[str, float, float], ...] = (
    ("theta_bias_rad", -math.pi, math.pi), ("theta_sigma_rad", 0.0, math.pi), ("rate_sigma_rad_s", 0.0, 10.0),
    ("rate_delay_s", 0.0, 60.0), ("latency_s", 0.0, 60.0), ("valid_fraction", 0.0, 1.0))
"""The valid range of each float field of :class:`TrackerNoiseModel` (rad, rad/s, s, fraction): angles
within half a turn, rates to 10 rad/s (573 deg/s), delays to a minute."""


@dataclass(frozen=True)
class TrackerNoiseModel:
    """The tracker's errors about y, fitted from a run: Gaussian angle and rate errors, latency, validity.

    Attributes
    ----------
    theta_bias_rad, theta_sigma_rad : float
        Mean and standard deviation of the y-angle error (estimate - truth at mid-exposure).
    rate_sigma_rad_s : float
        Standard deviation of the rate error against the truth at the rate's time tag.
    rate_delay_s : float
        Mean delay of the rate's time tag behind mid-exposure.
    latency_s : float
        Mean time from mid-exposure to the result (half the exposure + processing).
    valid_fraction : float
        Fraction of frames tracked.
    frames : int
        Frames the fit used.
    """

    theta_bias_rad: float
    theta_sigma_rad: float
    rate_sigma_rad_s: float
    rate_delay_s: float
    latency_s: float
    valid_fraction: float
    frames: int

    def __post_init__(self) -> None:
        """Each field in its range (a file of another run, or edited by hand, may hold anything);
        InvalidInputError naming the first that is not."""
        for name, low, high in NOISE_MODEL_RANGES:
            value = checked_number(getattr(self, name), f"noise model {name}", low=low, high=high)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "frames", checked_count(self.frames, "noise model frames", 1))

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> TrackerNoiseModel:
        try:
            return cls(**{name: data[name] for name in cls.__dataclass_fields__})
        except (KeyError, TypeError) as exc:
            raise InvalidInputError(f"a tracker noise model needs the keys {', '.join(cls.__dataclass_fields__)}; "
                                    f"{exc}") from exc


def fit_noise_model(frames: list[FrameRecord], t_s: NDArray, omega_true_rad_s: NDArray) -> TrackerNoiseModel:
    """Fit :class:`TrackerNoiseModel` to a run's frames (truth rates ``omega_true_rad_s`` at times ``t_s``)."""
    ok = [f for f in frames if f.ok]
    if len(ok) < 2:
        raise InvalidInputError(f"fitting a tracker noise model needs at least 2 tracked frames, got {len(ok)}")
    theta_err = np.array([_wrap(f.theta_est_rad - f.theta_true_rad) for f in ok])
    rate_true = np.interp([f.t_rate_s for f in ok], t_s, omega_true_rad_s)
    rate_err = np.array([f.omega_est_rad_s for f in ok]) - rate_true
    return TrackerNoiseModel(float(theta_err.mean()), float(theta_err.std()), float(rate_err.std()),
                             float(np.mean([f.t_mid_s - f.t_rate_s for f in ok])),
                             float(np.mean([f.latency_s for f in ok])), len(ok) / len(frames), len(frames))


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class ModelTrackerFeedback(_FramedFeedback):
    """The star tracker as a noise model: truth + fitted Gaussian errors, at the tracker's timing."""

    name = "tracker-model"

    def __init__(self, setup: StarTrackerSetup, log: CommandLog, model: TrackerNoiseModel,
                 rng: np.random.Generator | int | None = None):
        super().__init__(setup, log)
        self.model = model
        self.rng = np.random.default_rng(rng)

    def _measure(self, k: int, t_s: float, rot: Rotation, rate: NDArray) -> tuple[Measurement | None, FrameRecord]:
        m = self.model
        ok = bool(self.rng.random() < m.valid_fraction)
        d_theta = m.theta_bias_rad + m.theta_sigma_rad * float(self.rng.standard_normal())
        est_rot = rot * Rotation.from_rotvec([0.0, d_theta, 0.0])
        est_rate = rate + np.array([0.0, m.rate_sigma_rad_s * float(self.rng.standard_normal()), 0.0])
        available = t_s + m.latency_s
        record = FrameRecord(k, t_s, available, t_s, ok, "model", "" if ok else "modelled loss", 0, math.nan, 0.0,
                             y_angle(rot), y_angle(est_rot) if ok else math.nan, float(est_rate[1]) if ok else math.nan)
        return (Measurement(t_s, t_s, available, est_rot, est_rate) if ok else None), record
