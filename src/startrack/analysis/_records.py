"""What the post-processing analyses read: one :class:`ImageRecord` per processed image.

A *result set* is a sequence of records: the images of one folder, one batch of the browser tool
(``startrack.web``), or one campaign's re-runs. The analyses of Fowler 2013 ch. 8 take result sets
and give figures with the numbers behind them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..results import AttitudeSolution

if TYPE_CHECKING:
    from astropy.time import Time
    from scipy.spatial.transform import Rotation

    from ..calibrate import Site
    from ..camera import Camera
    from ..simulate import Truth


@dataclass(frozen=True, eq=False)
class ImageRecord:
    """One image and what the pipeline made of it.

    Attributes
    ----------
    name : str
        A label for tables and figures (usually the file name).
    solution : AttitudeSolution
        The solve, with its ``detections`` (``matches.det_index`` indexes them) and ``camera``.
    image : ndarray, shape (H, W), optional
        The pixels (counts) the detections were made on; needed by the image histograms and the
        spot gallery.
    truth : startrack.simulate._truth.Truth, optional
        The simulator's truth, for a simulated image.
    time : astropy.time.Time, optional
        When the image was taken (ground photos: the repeatability analysis needs it).
    settings : mapping
        The options the image was processed with (detection settings, camera, corrections), as
        plain JSON-able values, so that tables can show what differed between result sets.
        The keys :func:`startrack.analysis.postprocess.records_from_images` writes and the
        re-running analyses read are listed in ``docs/analysis.md``.
    path : pathlib.Path, optional
        The file the image was read from, so that its pixels can be read again when ``image``
        was not kept.
    camera : startrack.camera.Camera, optional
        The calibrated camera given to the solve (None when the field of view was searched);
        the lens model of the correction analysis and of re-runs.
    site : startrack.calibrate._sites.Site, optional
        Where a photo from the ground was taken (refraction, fixed-mount repeatability).
    true_rot_cam_from_icrs : scipy.spatial.transform.Rotation, optional
        The true attitude when it is known without a full ``truth`` (read from the header or
        the ``.truth.json`` sidecar of a file written by ``startrack simulate``).
    """

    name: str
    solution: AttitudeSolution
    image: NDArray[np.floating | np.integer] | None = None
    truth: Truth | None = None
    time: Time | None = None
    settings: Mapping[str, Any] = field(default_factory=dict)
    path: Path | None = None
    camera: Camera | None = None
    site: Site | None = None
    true_rot_cam_from_icrs: Rotation | None = None
