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

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._cubesat import CubeSat
    from ._estimate import CommandLog
    from ._field import DipoleField
    from ._guidance import HORIZONS, GuidanceOptions
    from ._loop import FEEDBACKS, FIELDS, PLANTS, LoopConfig, RunRecord, run_loop
    from ._metrics import METRIC_KEYS, SEED_POWER_W, SEED_TABLE_5_3, StepMetrics, run_metrics
    from ._planner import Boundary
    from ._plant import ThreeAxisPlant
    from ._plots import save_run_plots
    from ._report import summary, table, write_files
    from ._scenario import Scenario
    from ._star_tracker_feedback import MAX_LATENCY_S, StarTrackerSetup, TrackerNoiseModel, fit_noise_model

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
