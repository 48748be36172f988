"""startrack: an open star-tracker system.

From photons on a detector to a spacecraft's attitude and rate, and from a photo of the night sky
to where the camera pointed. See ``docs/conventions.md`` for the pixel, frame and rotation
conventions every function keeps.
"""

from __future__ import annotations

from .camera import Camera, get_preset
from .multihead import RigSolution, solve_rig
from .results import AttitudeSolution, Detections, StarMatches, Status
from .rig import CameraRig, RigHead
from .solve import solve_image, solve_stars

__version__ = "0.1.0"

__all__ = [
    "AttitudeSolution",
    "Camera",
    "CameraRig",
    "Detections",
    "RigHead",
    "RigSolution",
    "StarMatches",
    "Status",
    "__version__",
    "get_preset",
    "solve_image",
    "solve_rig",
    "solve_stars",
]
