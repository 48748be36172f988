"""Star trackers with several heads or a split field of view: one attitude from all cameras, star
by star (issue 18; Samaan 2002 Eq. 4–5).

The rig itself (:class:`startrack.CameraRig`, :class:`startrack.RigHead`) lives in
:mod:`startrack.rig`. This package holds what works on it:

solve        :func:`solve_rig`: lost-in-space on the head that can be solved, the others through
             their mountings as in tracking mode, or a joint pattern across heads
pattern      identification on the combined star set when no head can be identified alone
predict      stars predicted through a mounting and matched in windows
joint        one weighted Wahba fit in the body frame, per-head own solutions, consistency
stars        the star lists of the heads, checked against the rig
split_fov    the field of each spot of a split-FOV frame from its intensity-weighted second moments
images       :func:`solve_rig_images`: detect, classify split fields, solve
tracking     :class:`RigTracker`, the rig mode of :class:`startrack.track.Tracker`
mounting     in-flight mounting calibration against a reference head, and drift detection
exclusion    Sun, Earth-limb and Moon exclusion of each head
availability fraction of pointings where a head, and the joint solution, has enough stars
report       a RigSolution as JSON values and a table (``startrack solve-rig``)

``docs/rig.md`` describes them, with measured figures.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "RigAvailability": ".availability",
    "rig_availability": ".availability",
    "BrightBodies": ".exclusion",
    "blinded_by": ".exclusion",
    "dawn_dusk_bodies": ".exclusion",
    "detector_stars": ".images",
    "solve_rig_images": ".images",
    "MountingEstimate": ".mounting",
    "calibrate_mountings": ".mounting",
    "recalibrated": ".mounting",
    "rig_solution_table": ".report",
    "rig_solution_to_dict": ".report",
    "IDENTIFIED_BY_HEAD": ".solution",
    "IDENTIFIED_JOINTLY": ".solution",
    "RigOptions": ".solution",
    "RigSolution": ".solution",
    "check_method": ".solve",
    "consistency_chi2": ".solve",
    "solve_head_stars": ".solve",
    "solve_rig": ".solve",
    "FieldClassification": ".split_fov",
    "classify_fields": ".split_fov",
    "moments_radius_px": ".split_fov",
    "spot_moments": ".split_fov",
    "HeadStars": ".stars",
    "RigTrackStep": ".tracking",
    "RigTracker": ".tracking",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
