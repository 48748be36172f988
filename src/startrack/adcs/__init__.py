"""Closed-loop attitude control with the star tracker in the loop: Sease 2013 chapter 5 as a
runnable demonstration (``docs/adcs.md``).

A consumer of the library: the core never imports this package (DESIGN.md §2).

Modules
-------
cubesat         the KnightCube's inertia, torque coil and test-bed field
field           uniform (Helmholtz) and centred-dipole fields
plant           single-axis and three-axis plants, integrated with scipy
lgl             Legendre-Gauss-Lobatto nodes, weights, differentiation matrix
planner         minimum coil energy by virtual motion camouflage, SLSQP
guidance        receding-horizon replanning
control         error quaternion, input-output linearisation, LQR, the PD baseline
actuation       wanted acceleration -> coil currents
estimate        measurements, estimates, propagation with the commanded accelerations
feedback        truth and IMU feedback
star_tracker_feedback  startrack in the loop (images -> detection -> Tracker), and a fitted model
scenario        the seed's 700 s run of seven +0.1 steps in q2
loop            the closed loop at 40 Hz
metrics         rise, overshoot, settling, steady-state error, power
plots           the figures of a run
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "CubeSat": ".cubesat",
    "CommandLog": ".estimate",
    "DipoleField": ".field",
    "GuidanceOptions": ".guidance",
    "HORIZONS": ".guidance",
    "FEEDBACKS": ".loop",
    "FIELDS": ".loop",
    "LoopConfig": ".loop",
    "PLANTS": ".loop",
    "RunRecord": ".loop",
    "run_loop": ".loop",
    "METRIC_KEYS": ".metrics",
    "SEED_POWER_W": ".metrics",
    "SEED_TABLE_5_3": ".metrics",
    "StepMetrics": ".metrics",
    "run_metrics": ".metrics",
    "Boundary": ".planner",
    "ThreeAxisPlant": ".plant",
    "save_run_plots": ".plots",
    "summary": ".report",
    "table": ".report",
    "write_files": ".report",
    "Scenario": ".scenario",
    "StarTrackerSetup": ".star_tracker_feedback",
    "TrackerNoiseModel": ".star_tracker_feedback",
    "fit_noise_model": ".star_tracker_feedback",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
