"""The smear of a streaked frame and the limits of the Tracker's streak mode (issue 19; Samaan 2002
Table 1; Sease 2013 ): the smear measured in an image before there is a rate, the
smear limits an exposure sets, and whether a streak frame's rate is precise enough to predict the
next frame by. Used by :class:`startrack.track.Tracker`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class SmearLimits:
    """How an exposure smears the stars (:meth:`Tracker.smear_limits`).

    Attributes
    ----------
    exposure_s : float
    pixel_arcsec : float
        One pixel at the boresight.
    max_rate_deg_s : float
        Largest rate across the boresight that smears a star by at most 0.1 px (Samaan 2002
        Table 1, :func:`startrack.simulate._snr.max_rate_rad_s`).
    streak_on_px, streak_on_deg_s, streak_off_px, streak_off_deg_s : float
        The smear (px) at which the Tracker enters streak mode and leaves it again, and the rates
        across the boresight (deg/s) that make it.
    """

    exposure_s: float
    pixel_arcsec: float
    max_rate_deg_s: float
    streak_on_px: float
    streak_on_deg_s: float
    streak_off_px: float
    streak_off_deg_s: float

    def describe(self) -> str:
        """One line for a user (``startrack track``)."""
        return (f"smear limit (Samaan 2002 Table 1): exposure {self.exposure_s:g} s, 1 px = {self.pixel_arcsec:.1f} "
                f"arcsec: 0.1 px of smear at {self.max_rate_deg_s:.4g} deg/s across the boresight; streak mode from "
                f"{self.streak_on_px:g} px ({self.streak_on_deg_s:.3g} deg/s), point mode again below "
                f"{self.streak_off_px:g} px ({self.streak_off_deg_s:.3g} deg/s)")


POINT_MOMENT_BINS = 1.6
"""The moment length of a point star's candidate on the binned grid of
:func:`startrack.rate._streak_find.find_streak_candidates`, in bins: the major axis of a round
blob picks up the noise (6-7 px at 4 px bins on unsmeared generic-cmos frames, 12 and 20 deg
fields, measured); :func:`image_smear_px` takes it out in quadrature."""
SMEAR_CANDIDATES = 20


def image_smear_px(data: NDArray) -> float:
    """The smear (px) of a frame measured in the image: the lower quartile of the moment lengths
    of its :data:`SMEAR_CANDIDATES` brightest streak candidates (blends of two stars and the
    brightest stars' wide wings measure longer, never shorter), the point-star length
    (:data:`POINT_MOMENT_BINS`) taken out in quadrature. 0 when the frame has no candidate.

    A smear found that way is measured again at full resolution (the median length of the
    brightest spots, :func:`startrack.rate._streak_detect.median_length_px`, as
    :func:`startrack.rate.choose_mode` measures it) and the smaller taken: on a dense or small
    frame the candidates' bins merge most neighbouring stars, and a still frame then seemed
    smeared, sending the Tracker's first frame to a streak solve before the point solve that
    found it (``tests/rate/test_rate_image_smear.py``)."""
    from ._streak_detect import median_length_px
    from ._streak_find import find_streak_candidates

    found = find_streak_candidates(data)
    if not len(found):
        return 0.0
    quartile = float(np.percentile(found.length_px[:SMEAR_CANDIDATES], 25))
    binned = math.sqrt(max(quartile**2 - (POINT_MOMENT_BINS * found.bin_px) ** 2, 0.0))
    full = median_length_px(data, SMEAR_CANDIDATES)  # NaN when nothing is found: nothing to contradict
    return binned if binned == 0 or np.isnan(full) else min(binned, full)


PREDICTION_RATE_UNCERTAINTY = 0.3
"""Largest 3-sigma uncertainty (fraction of the rate) of a streak frame's rate, trusted or not,
that the Tracker still prefers to the rate differenced from the attitudes: under an angular
acceleration the smoothed difference lags by ``(1 - rate_gain) / rate_gain`` frame periods (a
tracker slewing at 4 deg/s^2 with 5 frames a second and gain 0.5 was 0.8 deg/s behind), while the
streaks give the rate at this frame's mid-exposure."""


def usable_for_prediction(solution) -> bool:
    """Whether an untrusted streak rate is still precise enough to predict the next frame by."""
    cov, turn = solution.rate.covariance_rad2_s2, solution.turn_rad
    if cov is None or not np.all(np.isfinite(turn)) or not math.isfinite(solution.exposure_s):
        return False
    norm = float(np.linalg.norm(turn)) / solution.exposure_s
    trace = float(np.trace(cov))
    return math.isfinite(trace) and norm > 0 and 3.0 * math.sqrt(max(trace, 0.0)) <= PREDICTION_RATE_UNCERTAINTY * norm
