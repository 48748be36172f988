"""The closed loop: feedback -> estimate -> guidance -> tracking law -> coils -> plant, at 40 Hz.

Each tick (period dt): the feedback source gives the estimate at t; the guidance returns the
plan (replanning when due); the law asks for an angular acceleration about y (on the three-axis
plant, a PD on the same gains holds the x and z angles at zero); the coils get the currents
(:func:`.actuation.allocate` with the field the controller expects at the estimated attitude) and
the expected acceleration is logged for the propagation of late measurements; the plant then
runs for dt with the delivered currents (commanded + the PWM error, uniform within
``current_noise_a``, while the coils are on), and any camera frame whose mid-exposure falls in
that period is rendered from the true state at that instant. Until the first measurement the
coils are off.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError, check_int, require
from ._actuation import allocate
from ._control import tracking_law
from ._cubesat import CubeSat
from ._estimate import CommandLog, Estimate
from ._feedback import Feedback, ImuFeedback, TruthFeedback
from ._field import DipoleField, UniformField
from ._guidance import Guidance, GuidanceOptions, PlanEvent
from ._plant import Plant, SingleAxisPlant, ThreeAxisPlant, coil_torque_body, y_rotation
from ._scenario import Scenario
from ._star_tracker_feedback import (
    FrameRecord,
    ModelTrackerFeedback,
    StarTrackerFeedback,
    StarTrackerSetup,
    TrackerNoiseModel,
)

FEEDBACKS = ("truth", "imu", "tracker", "tracker-model")
PLANTS = ("single-axis", "three-axis")
FIELDS = ("helmholtz", "dipole")
RECORDED = ("theta_true", "omega_true", "theta_est", "omega_est", "est_valid", "est_age", "plan_theta",
            "plan_omega", "target_theta", "current_cmd", "current_delivered", "torque_y", "power_w", "off_axis")


@dataclass(frozen=True)
class LoopConfig:
    """Everything a run needs.

    Parameters
    ----------
    feedback : str
        "truth", "imu", "tracker" (startrack in the loop) or "tracker-model" (needs ``noise_model``).
    law : str
        "lqr" (seed) or "pd" (baseline).
    plant : str
        "single-axis" (seed) or "three-axis".
    b_field : str
        Three-axis only: "helmholtz" (the test bed's 4.5 G along reference x) or "dipole".
    seed : int
        Seed of the IMU noise, the PWM error and the image noise.
    """

    cubesat: CubeSat = field(default_factory=CubeSat)
    scenario: Scenario = field(default_factory=Scenario)
    guidance: GuidanceOptions = field(default_factory=GuidanceOptions)
    feedback: str = "truth"
    law: str = "lqr"
    plant: str = "single-axis"
    b_field: str = "helmholtz"
    tracker: StarTrackerSetup = field(default_factory=StarTrackerSetup)
    noise_model: TrackerNoiseModel | None = None
    q_weight: float = 20.0
    r_weight: float = 1.0
    seed: int = 0

    def __post_init__(self) -> None:
        for name, valid in (("feedback", FEEDBACKS), ("plant", PLANTS), ("b_field", FIELDS)):
            if getattr(self, name) not in valid:
                raise InvalidInputError(f"{name} must be one of {', '.join(valid)}, got {getattr(self, name)!r}")
        check_int(self, ("seed",), 0)
        if self.feedback == "tracker-model" and self.noise_model is None:
            raise InvalidInputError("feedback 'tracker-model' needs a noise_model (fitted from a tracker run)")
        if self.plant == "single-axis" and self.b_field != "helmholtz":
            raise InvalidInputError("the single-axis plant turns in the Helmholtz field; use plant='three-axis'")


@dataclass(frozen=True)
class RunRecord:
    """A run, tick by tick (arrays of shape (n,), angles rad, rates rad/s, currents A, torque N m).

    ``current_cmd`` / ``current_delivered`` are the y-torque coil's (single-axis) or the largest
    magnitude of the three; ``power_w`` sums I^2 R over the coils; ``off_axis`` is the angle of
    the true body y axis from the reference y axis (0 on the single-axis plant).
    """

    config: LoopConfig
    t_s: NDArray[np.float64]
    series: dict[str, NDArray[np.float64]]
    frames: list[FrameRecord]
    plans: list[PlanEvent]
    wall_s: float

    def __getattr__(self, name: str) -> NDArray[np.float64]:
        series = self.__dict__.get("series", {})
        if name in series:
            return series[name]
        raise AttributeError(name)


def make_plant(config: LoopConfig) -> Plant:
    sc, sat = config.scenario, config.cubesat
    theta0 = 2.0 * math.asin(sc.q2_start)
    if config.plant == "single-axis":
        return SingleAxisPlant(sat, theta0, sc.omega_start_rad_s)
    field_model = UniformField((sat.field_t, 0.0, 0.0)) if config.b_field == "helmholtz" else DipoleField()
    return ThreeAxisPlant(sat, field_model, y_rotation(theta0), (0.0, sc.omega_start_rad_s, 0.0))


def make_feedback(config: LoopConfig, log: CommandLog) -> Feedback:
    rng = np.random.default_rng([config.seed, 1])
    if config.feedback == "truth":
        return TruthFeedback()
    if config.feedback == "imu":
        return ImuFeedback(rng)
    if config.feedback == "tracker":
        return StarTrackerFeedback(config.tracker, log)
    return ModelTrackerFeedback(config.tracker, log, require(config.noise_model, "noise_model"), rng)


class _Controller:
    """Guidance + law + allocation for one tick."""

    def __init__(self, config: LoopConfig, plant: Plant):
        self.config, self.plant = config, plant
        self.law = tracking_law(config.law, config.q_weight, config.r_weight)
        self.guidance = Guidance(config.cubesat, config.guidance)

    def command(self, t: float, est: Estimate, target_q2: float) -> tuple[NDArray, NDArray, tuple]:
        """(currents, expected torque, plan sample) for the estimate; coils off when it is invalid."""
        n_coils = self.plant.coil_normals_body.shape[0]
        if not est.valid:
            return np.zeros(n_coils), np.zeros(3), (math.nan, math.nan, math.nan)
        theta, omega = est.theta_rad, est.omega_rad_s
        plan = self.guidance.update(t, theta, omega, target_q2).sample(t)
        accel = np.zeros(3)
        accel[1] = self.law.accel(theta, omega, plan)
        if n_coils == 3:
            tilt = (y_rotation(theta).inv() * est.rot_ref_from_body).as_rotvec()
            kp, kd = self.law.k_angle, self.law.k_rate
            accel[[0, 2]] = -(kp * tilt[[0, 2]] + kd * est.rate_body_rad_s[[0, 2]])
        b_body = est.rot_ref_from_body.inv().apply(self.plant.field.field_ref(t))
        currents, torque = allocate(self.config.cubesat, self.plant.coil_normals_body, b_body, accel,
                                    self.law.field_compensated)
        return currents, torque, plan


def run_loop(config: LoopConfig, progress=None) -> RunRecord:
    """Run the closed loop of ``config``; ``progress(done, total)`` is called every simulated second."""
    sc, sat = config.scenario, config.cubesat
    plant, log = make_plant(config), CommandLog()
    feedback, controller = make_feedback(config, log), _Controller(config, plant)
    pwm = np.random.default_rng([config.seed, 2])
    n, dt = sc.n_ticks, sc.dt_s
    t_s = np.arange(n, dtype=np.float64) * dt
    rec = {name: np.full(n, np.nan) for name in RECORDED}
    inertia = np.asarray(sat.inertia_kg_m2)
    wall = time.perf_counter()
    for j in range(n):
        t = float(t_s[j])
        est = feedback.estimate(t, plant, log)
        target = sc.target_at(t)
        currents, torque, plan = controller.command(t, est, target)
        log.append(t, torque / inertia)
        noise = pwm.uniform(-sat.current_noise_a, sat.current_noise_a, currents.size)
        delivered = currents + noise if est.valid else currents  # no PWM while the coils are off
        _record(rec, j, plant, est, plan, target, currents, delivered)
        times = feedback.sample_times(t, t + dt)
        for tt, (rot, rate) in zip(times, plant.step(delivered, dt, times), strict=True):
            feedback.observe(tt, rot, rate)
        if progress is not None and (j + 1) % round(1 / dt) == 0:
            progress(round((j + 1) * dt), round(n * dt))
    return RunRecord(config, t_s, rec, list(getattr(feedback, "frames", [])), controller.guidance.events,
                     time.perf_counter() - wall)


def _record(rec: dict, j: int, plant: Plant, est: Estimate, plan: tuple, target_q2: float,
            currents: NDArray, delivered: NDArray) -> None:
    from ._estimate import y_angle

    rot = plant.rot_ref_from_body()
    b_body = rot.inv().apply(plant.field.field_ref(plant.t_s))
    sat = plant.cubesat
    torque = coil_torque_body(delivered, plant.coil_normals_body, sat.moment_per_amp, b_body)
    pick = 0 if currents.size == 1 else int(np.argmax(np.abs(currents)))
    y_axis = rot.apply([0.0, 1.0, 0.0])
    values = {"theta_true": y_angle(rot), "omega_true": float(plant.rate_body()[1]),
              "theta_est": est.theta_rad if est.valid else math.nan,
              "omega_est": est.omega_rad_s if est.valid else math.nan, "est_valid": float(est.valid),
              "est_age": est.age_s, "plan_theta": plan[0], "plan_omega": plan[1],
              "target_theta": 2.0 * math.asin(target_q2), "current_cmd": float(currents[pick]),
              "current_delivered": float(delivered[pick]), "torque_y": float(torque[1]),
              "power_w": float(delivered @ delivered) * sat.resistance_ohm,
              "off_axis": math.atan2(math.hypot(y_axis[0], y_axis[2]), y_axis[1])}
    for name, value in values.items():
        rec[name][j] = value
