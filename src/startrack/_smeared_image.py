"""A smeared frame in :func:`startrack.solve_image` (issue 19 item 1): when to solve it from its
streaks (the elongation of its brightest spots), the call of :func:`startrack.rate.solve_streaked`
with what the image header says, and the streaks as the solution's detections."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .camera import Camera
from .results import Detections

if TYPE_CHECKING:  # the streak solver is imported by the calls that use it: solve_image imports
    # this module for every image, and a still frame never needs the solver
    from .identify import MethodName
    from .rate import StreakSolution

SMEARED_ELONGATION = 3.0
"""Median elongation (long over short axis of the second moments) of a frame's 10 brightest
detections from which :func:`startrack.solve_image` solves the frame from its streaks first:
chosen on simulated generic-cmos frames of a 12 deg field between the smears where the point
solve still holds and those where it is already far off or finds no match (the point and streak
solves of such frames: docs/attitude_and_rate.md). From :data:`SOME_ELONGATION` the streaks are
tried when the point solve fails."""
SOME_ELONGATION = 1.5


def smear_elongation(detections) -> float:
    """The median elongation of the 10 brightest detections (1.0 when there are none)."""
    values = np.asarray(detections.elongation, dtype=float)[:10]
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else 1.0


def solve_smeared_image(image, header, *, camera: Camera | None, fov_deg: float | None,
                        fov_range_deg: tuple[float, float] | None, epoch, method: MethodName,
                        pixel_aspect: float | tuple[float, float] | None) -> StreakSolution:
    """:func:`solve_streaked` for :func:`startrack.solve_image`: the exposure from the image header
    (:func:`header_exposure_s`; without one the rate is per exposure, ``turn_rad``) and the
    pixel aspect as :func:`startrack.solve_stars` takes it (a number fixes it, a range fits it)."""
    from .rate import StreakOptions, header_exposure_s, solve_streaked

    aspect = 1.0 if pixel_aspect is None else (None if isinstance(pixel_aspect, tuple | list) else float(pixel_aspect))
    kwargs = {"camera": camera} if camera is not None else {"fov_deg": fov_deg, "fov_range_deg": fov_range_deg}
    return solve_streaked(image, exposure_s=header_exposure_s(header), epoch=epoch,
                          options=StreakOptions(pixel_aspect=aspect), method=method, **kwargs)


def streak_detections(solution: StreakSolution, width: int, height: int, noise: float = 0.0,
                      background: float = 0.0) -> Detections:
    """The fitted streaks of a solution as :class:`startrack.results.Detections` (one per row of
    ``solution.streaks``, so that ``matches.det_index`` indexes them): the light centroids (the
    mid-exposure positions, px), the fitted light, the larger end sigma, the elongation length
    over the blur's FWHM and a point quality of 0 (streaks, not point sources)."""
    fits = solution.streaks
    if fits is None or not len(fits):
        return Detections(width=int(width), height=int(height), noise=noise, background=background)
    centroid = fits.measurements()[0][:, 4:6]
    n = len(fits)
    with np.errstate(invalid="ignore", divide="ignore"):
        elongation = np.maximum(1.0, fits.length_px / (2.355 * fits.blur_px))
    return Detections(x=centroid[:, 0].copy(), y=centroid[:, 1].copy(), flux=np.asarray(fits.flux, dtype=float),
                      sigma_px=np.max(fits.end_sigma_px(), axis=1), area_px=np.zeros(n, dtype=np.int64),
                      peak=np.full(n, np.nan), elongation=elongation, background=background, noise=noise,
                      width=int(width), height=int(height), point_quality=np.zeros(n))


def image_solution(solution: StreakSolution, found: Detections, detect_s: float, epoch_source: str) -> StreakSolution:
    """A streak solution as :func:`startrack.solve_image` returns it: the detection time added, its
    streaks as the detections (:func:`streak_detections`; ``found`` gives the size and noise) and
    the epoch's source as :func:`startrack.solve_image` resolved it (the streak solve was given the
    year alone, so it says "given" even for a header's epoch)."""
    detections = streak_detections(solution, found.width, found.height, found.noise, found.background)
    return replace(solution, solve_time_s=detect_s + solution.solve_time_s, detections=detections,
                   epoch_source=epoch_source)
