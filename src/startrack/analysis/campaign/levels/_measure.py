"""Helpers of the levels that measure something other than an attitude (star counts, centroids,
photometry, detection time, smear): their common columns, and truth-to-detection matching.

Such a trial has no attitude solution, so :func:`measurement_columns` fills the common columns
of :data:`~startrack.analysis.campaign._outcome.COLUMNS` this way (``docs/campaigns.md``):
``status`` is "OK" when the trial measured what it should and a :class:`~startrack.results.Status`
name saying why not otherwise (``TOO_FEW_STARS``); ``solved`` is ``status == "OK"``;
``correct`` is the level's own judgement (documented with the level); the attitude errors, the
solver's sigmas and ``false_match_prob`` are NaN (there is no identification); ``n_stars`` and
``n_matched`` count what the level says (detections and true stars found, stars in the field);
``time_s`` is the timed stage; ``ra_deg``, ``dec_deg``, ``roll_deg`` give the trial's attitude
where it sets the scene, else NaN.

The module name starts with an underscore, so it is not taken for a level.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ....errors import InvalidInputError
from .._outcome import NAN, truth_columns
from .._params import SpecError


def measurement_columns(*, status: str, correct: bool, n_stars: int, n_matched: int, time_s: float,
                        rot_cam_from_icrs: Rotation | None = None) -> dict[str, Any]:
    """The common columns of a trial without an attitude solution (see the module docstring)."""
    row = {"status": status, "error": "", "solved": status == "OK", "correct": bool(correct),
           "err_x_arcsec": NAN, "err_y_arcsec": NAN, "err_roll_arcsec": NAN, "err_cross_arcsec": NAN,
           "err_total_arcsec": NAN, "sigma_cross_arcsec": NAN, "sigma_roll_arcsec": NAN,
           "n_stars": int(n_stars), "n_matched": int(n_matched), "false_match_prob": NAN,
           "time_s": float(time_s)}
    row.update(truth_columns(rot_cam_from_icrs))
    return row


def match_truth(x_true: NDArray, y_true: NDArray, x: NDArray, y: NDArray, radius_px: float) -> NDArray[np.intp]:
    """For each true star, the index of its detection within ``radius_px`` (-1 when none).

    Each detection is used once at most, nearest pairs first, so a detection between two true
    stars is given to the nearer one.

    Parameters
    ----------
    x_true, y_true : ndarray, shape (N,)
        True positions (px).
    x, y : ndarray, shape (M,)
        Detected positions (px).
    radius_px : float

    Returns
    -------
    ndarray of int, shape (N,)
    """
    index = np.full(np.size(x_true), -1, dtype=np.intp)
    if np.size(x) == 0 or np.size(x_true) == 0:
        return index
    pairs = cKDTree(np.column_stack([x_true, y_true])).sparse_distance_matrix(
        cKDTree(np.column_stack([x, y])), radius_px, output_type="ndarray")
    used = np.zeros(np.size(x), dtype=bool)
    for i, j, _ in sorted(pairs.tolist(), key=lambda p: p[2]):
        i, j = int(i), int(j)
        if index[i] < 0 and not used[j]:
            index[i], used[j] = j, True
    return index


def check_builds(params: Mapping[str, Any], *builders: Callable[[Mapping[str, Any]], Any]) -> None:
    """Build each object of a cell once (``frame_sensor``, ``frame_detector``, ...), so that a value
    it refuses is reported before any work, naming the object.

    Raises
    ------
    SpecError
    """
    for build in builders:
        try:
            build(params)
        except (InvalidInputError, ValueError, TypeError) as exc:
            raise SpecError(f"{build.__name__.removeprefix('frame_')} settings: {exc}") from None
