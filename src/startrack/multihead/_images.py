"""``solve_rig_images``: detect the stars of every detector of a rig, classify the spots of split
detectors by field (:mod:`._split_fov`), and solve the rig (:func:`.solve.solve_rig`).

A head with its own detector takes its detections as its star list. A split detector's detections
are classified by their intensity-weighted second moments; each field's list holds the spots
classified there and the ambiguous ones (tried in both fields; the solver keeps a spot matched in
both in the field whose prediction is closer). ``det_index`` in the result indexes the detector's
detections.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InvalidInputError
from ..results import Detections
from ..rig import CameraRig
from ..solve import epoch_jyear
from ._solution import RigOptions, RigSolution
from ._solve import check_method, solve_head_stars
from ._split_fov import DEFAULT_MARGIN, FieldClassification, classify_fields, moments_radius_px, spot_moments
from ._stars import HeadStars

if TYPE_CHECKING:
    from astropy.time import Time

    from ..identify import MethodName
    from ..io import Image


def detector_stars(image, rig: CameraRig, detector_name: str, detector=None, margin: float = DEFAULT_MARGIN,
                   weighting: str = "intensity") -> tuple[dict[str, HeadStars], Detections, FieldClassification | None]:
    """The star lists of the heads on one detector, its detections and (split detectors) the
    field classification."""
    from ..detect import StarDetector

    heads = rig.detectors[detector_name]
    image = _as_image(image)
    data = image if isinstance(image, np.ndarray) else image.data
    size = (heads[0].camera.width, heads[0].camera.height)
    if data.shape[:2] != size[::-1]:
        raise InvalidInputError(f"detector {detector_name!r}: the image is {data.shape[1]} x {data.shape[0]} px, "
                                f"its camera {size[0]} x {size[1]} px")
    found = (detector or StarDetector()).detect(image)  # an Image: with a JPEG's noise floor
    if len(heads) == 1:
        return {heads[0].name: HeadStars.of(heads[0], found.x, found.y, found.flux)}, found, None
    moments = spot_moments(data, found.x, found.y, background=found.background, noise=found.noise,
                           radius_px=moments_radius_px(heads), weighting=weighting)
    fields = classify_fields(moments, heads, margin)
    out = {}
    for head in heads:
        idx = fields.members(head.name)
        out[head.name] = HeadStars.of(head, found.x[idx], found.y[idx], found.flux[idx], index=idx)
    return out, found, fields


def _as_image(image) -> np.ndarray | Image:
    """An ndarray or a :class:`startrack.io.Image` as it is, a path read."""
    from ..io import Image, read_image

    return image if isinstance(image, np.ndarray | Image) else read_image(image)


def solve_rig_images(images: Mapping[str, object], rig: CameraRig, *, epoch: Time | float | None = None,
                     method: MethodName = "quads",
                     options: RigOptions | None = None, detector=None,
                     margin: float = DEFAULT_MARGIN) -> RigSolution:
    """Detect, classify and solve one exposure of a rig.

    Parameters
    ----------
    images : mapping of str to image
        Detector name (a head's name, or a split detector's) to its image: a path, an ndarray or a
        :class:`startrack.io.Image`.
    rig : CameraRig
    epoch, method, options
        As in :func:`startrack.solve_rig`.
    detector : startrack.detect.StarDetector, optional
        Detection settings for every detector.
    margin : float
        Ambiguity margin of the split-field classification (:func:`.split_fov.classify_fields`).

    Returns
    -------
    RigSolution
        With ``detections`` (per detector) and ``fields`` (the classification of split detectors).
    """
    method = check_method(method)
    detectors = rig.detectors
    unknown = [name for name in images if name not in detectors]
    if unknown:
        raise InvalidInputError(f"image for {unknown[0]!r}, which is not a detector of the rig (detectors: "
                                f"{', '.join(detectors)})")
    stars = {h.name: HeadStars.of(h, np.zeros(0), np.zeros(0)) for h in rig}
    found, fields = {}, {}
    for name, image in images.items():
        part, found[name], classified = detector_stars(image, rig, name, detector, margin)
        stars.update(part)
        if classified is not None:
            fields[name] = classified
    solution = solve_head_stars(stars, rig, epoch_jyear(epoch), method, options or RigOptions())
    return replace(solution, detections=found, fields=fields)
