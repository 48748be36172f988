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

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._availability import RigAvailability, rig_availability
    from ._exclusion import BrightBodies, blinded_by, dawn_dusk_bodies
    from ._images import detector_stars, solve_rig_images
    from ._mounting import MountingEstimate, calibrate_mountings, recalibrated
    from ._report import rig_solution_table, rig_solution_to_dict
    from ._solution import IDENTIFIED_BY_HEAD, IDENTIFIED_JOINTLY, RigOptions, RigSolution
    from ._solve import RIG_METHODS, check_method, consistency_chi2, solve_head_stars, solve_rig
    from ._split_fov import FieldClassification, classify_fields, moments_radius_px, spot_moments
    from ._stars import HeadStars
    from ._tracking import RigTracker, RigTrackStep

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
