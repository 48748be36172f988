"""What the post-processing analyses read: one :class:`ImageRecord` per processed image.

A *result set* is a sequence of records: the images of one folder, one batch of the browser tool
(``startrack.web``), or one campaign's re-runs. The analyses of seed 003 ch. 8 (notes
``seed-003.md`` §1.11) take result sets and give figures with the numbers behind them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..results import AttitudeSolution

if TYPE_CHECKING:
    from astropy.time import Time

    from ..simulate.truth import Truth


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
    truth : startrack.simulate.truth.Truth, optional
        The simulator's truth, for a simulated image.
    time : astropy.time.Time, optional
        When the image was taken (ground photos: the repeatability analysis needs it).
    settings : mapping
        The options the image was processed with (detection settings, camera, corrections), as
        plain JSON-able values, so that tables can show what differed between result sets.
    """

    name: str
    solution: AttitudeSolution
    image: NDArray[np.floating | np.integer] | None = None
    truth: Truth | None = None
    time: Time | None = None
    settings: Mapping[str, Any] = field(default_factory=dict)
