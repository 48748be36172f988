"""A solve that calibrates itself: from an uncalibrated camera (a field-of-view range only) to a
calibrated camera and a better attitude, by solve -> calibrate -> re-solve.

1. Solve lost-in-space with the FOV range (focal length and, with enough stars, k1 are fitted by
   the solver).
2. Calibrate the camera on the matched stars (:func:`.stars.calibrate_from_stars`: focal length,
   principal point, distortion, attitude; outliers rejected, insignificant terms pruned).
   The calibrated terms are kept only if, jointly, they lower the residual significantly against
   the pinhole on the same stars (F-test, :func:`justified`); otherwise the pinhole is used.
3. Solve again with the calibrated camera: a better model matches more stars (the match radius is
   a few pixels), which calibrate again; stop when the matches stop growing.

The report compares, on the same stars (the final matches the calibrated model keeps), the
residual of the plain pinhole model (attitude + focal length, centred principal point) with the
residual of the calibrated model. With few stars only the most important parameters are fitted
(:func:`affordable_fit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import f as f_dist

from ..camera import Camera
from ..errors import require
from ..results import AttitudeSolution, Status
from ..solve import solve_image
from ._stars import DEFAULT_FIT, CalibrationFrame, CalibrationResult, calibrate_from_stars

PINHOLE_FIT = ("f",)
MAX_ROUNDS = 4
PRIORITY = ("f", "k1", "cx", "cy", "k2", "p1", "p2", "aspect", "k3")
"""Order in which parameters are admitted when there are few stars (largest effects first,
Jacobs 1995 §6.2: optical centre and focal length, then distortion)."""
STARS_PER_UNKNOWN = 1.5
"""At least this many stars (two residuals each) per unknown (parameters + 3 for the attitude)."""
SIGNIFICANCE = 0.001
"""The calibrated model replaces the pinhole only when its lower residual is significant at this
level for its terms jointly (F-test on the same stars, :func:`justified`). The per-term 3-sigma
rule alone can keep correlated terms on a few stars of a narrow field: on img3.png (6 deg, 12
stars) it kept a principal point 300-400 px off centre and k2 = -35, for an RMS of 0.264 px
against the pinhole's 0.286 px (F = 0.7 on 4 and 16 degrees of freedom). The level is stricter
than the textbook 0.01 because the terms tested are those the pruning chose on the same stars,
which makes the nominal p-value optimistic: img6.png (the same 6 deg camera, 17 stars) reached
p = 0.0045 with aspect, cx, k1 = -1.1 and k2 = 89, while the images whose distortion is plain
(crappy, orion_trees, pleiades, roof) give p = 1e-6 to 1e-44."""


@dataclass(frozen=True)
class SelfCalibration:
    """Outcome of :func:`self_calibrate`.

    Attributes
    ----------
    status : Status
    reason : str
    solution : AttitudeSolution
        The final solve, with the calibrated camera.
    calibration : CalibrationResult or None
        The final calibration (camera, uncertainties, pruned terms, outliers).
    pinhole_rms_px, calibrated_rms_px : float
        RMS residual distance of the pinhole and of the calibrated model on the same stars (the
        final matches less the calibration's outliers), pixels.
    pixel_scale_arcsec : float
        Angular size of a pixel at the principal point of the calibrated camera.
    n_pinhole, n_calibrated : int
        Stars in each residual.
    rounds : int
        Calibrate / re-solve rounds done.
    first_solve_rms_arcsec : float
        RMS residual that the first (uncalibrated) solve reported on all its matches.
    """

    status: Status
    reason: str
    solution: AttitudeSolution
    calibration: CalibrationResult | None = None
    pinhole_rms_px: float = float("nan")
    calibrated_rms_px: float = float("nan")
    pixel_scale_arcsec: float = float("nan")
    n_pinhole: int = 0
    n_calibrated: int = 0
    rounds: int = 0
    first_solve_rms_arcsec: float = float("nan")

    @property
    def pinhole_rms_arcsec(self) -> float:
        return self.pinhole_rms_px * self.pixel_scale_arcsec

    @property
    def calibrated_rms_arcsec(self) -> float:
        return self.calibrated_rms_px * self.pixel_scale_arcsec


def affordable_fit(fit: tuple[str, ...], n_stars: int) -> tuple[str, ...]:
    """The first parameters of ``fit`` in :data:`PRIORITY` order that ``n_stars`` stars can fix."""
    ordered = [name for name in PRIORITY if name in fit] + [name for name in fit if name not in PRIORITY]
    n = int(max(0, min(len(ordered), n_stars / STARS_PER_UNKNOWN - 3)))
    return tuple(ordered[:n])


def pinhole_of(camera: Camera) -> Camera:
    """The camera's focal length with a centred principal point, square pixels and no distortion:
    the start of every calibration, so that pruning always returns a term to its null value (not
    to what an earlier round, on other stars, made of it)."""
    return Camera(width=camera.width, height=camera.height, fx=camera.fx, fy=camera.fx)


def _camera_of(cal: CalibrationResult) -> Camera:
    """The camera of a calibration that succeeded."""
    return require(cal.camera, "the calibrated camera")


def _pinhole_on_the_same_stars(frame: CalibrationFrame, cal: CalibrationResult) -> CalibrationResult:
    """Attitude + focal length (no distortion, centred principal point) fitted by plain least
    squares to the stars the calibrated model kept."""
    keep = cal.inliers[0]
    sub = CalibrationFrame(frame.x[keep], frame.y[keep], frame.vectors_icrs[keep], cal.rotations[0])
    return calibrate_from_stars(sub, pinhole_of(_camera_of(cal)), fit=PINHOLE_FIT, prune=False, reject_sigma=np.inf)


def justified(frame: CalibrationFrame, cal: CalibrationResult) -> CalibrationResult:
    """``cal``, or the pinhole calibration (focal length only) of the same frame when the extra
    terms of ``cal`` do not lower the residual significantly (:data:`SIGNIFICANCE`).

    The F-test compares the residual sums of squares of both models on the stars ``cal`` kept:
    F = ((RSS_pinhole - RSS_cal) / (p_cal - p_pinhole)) / (RSS_cal / (n - p_cal)), with n the
    residuals (two per star) and p the unknowns (fitted terms plus three for the attitude).
    """
    extra_terms = len(cal.fitted) - len(PINHOLE_FIT)
    n_stars = int(np.count_nonzero(cal.inliers[0]))
    n_res, p_cal = 2 * n_stars, len(cal.fitted) + 3
    if extra_terms <= 0 or n_res <= p_cal:
        return cal
    same_stars = _pinhole_on_the_same_stars(frame, cal)
    rss_cal, rss_pinhole = n_stars * cal.rms_px**2, n_stars * same_stars.rms_px**2
    f_value = ((rss_pinhole - rss_cal) / extra_terms) / max(rss_cal / (n_res - p_cal), 1e-300)
    if f_dist.sf(f_value, extra_terms, n_res - p_cal) < SIGNIFICANCE:
        return cal
    return calibrate_from_stars(frame, pinhole_of(_camera_of(cal)), fit=PINHOLE_FIT, prune=False)


def _calibrated(frame: CalibrationFrame, camera: Camera, fit: tuple[str, ...]) -> CalibrationResult:
    """Calibration of the terms ``frame`` can afford, from the pinhole of ``camera``, if justified."""
    cal = calibrate_from_stars(frame, pinhole_of(camera), fit=affordable_fit(fit, len(frame)))
    return justified(frame, cal) if cal.status else cal


def self_calibrate(image, *, fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                   camera: Camera | None = None, fit: tuple[str, ...] = DEFAULT_FIT, epoch=None,
                   channel: str | int | None = None, max_rounds: int = MAX_ROUNDS) -> SelfCalibration:
    """Solve an image, calibrate the camera on its stars, re-solve; repeat while it helps.

    Parameters
    ----------
    image : path, ndarray or startrack.io.Image
    fov_deg, fov_range_deg, camera, epoch, channel
        As in :func:`startrack.solve_image` (for the first solve).
    fit : tuple of str
        Parameters to calibrate (:mod:`._lens_models`); the 3-sigma rule prunes the insignificant.
    max_rounds : int

    Returns
    -------
    SelfCalibration
        ``status`` is the first solve's when it fails.
    """
    from ..io import Image, read_image

    img = image if isinstance(image, Image) else read_image(image, channel=channel)
    solution = solve_image(img, fov_deg=fov_deg, fov_range_deg=fov_range_deg, camera=camera, epoch=epoch,
                           parity="normal")  # the calibration fits a plain camera
    if not solution.solved:
        return SelfCalibration(status=solution.status, reason=solution.reason, solution=solution)
    frame = CalibrationFrame.from_solution(solution)
    first_rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)))
    cal, rounds = None, 0
    for rounds in range(1, max_rounds + 1):  # noqa: B007 (rounds is reported)
        new_cal = _calibrated(frame, require(solution.camera, "the solution's camera"), fit)
        if not new_cal.status:
            break
        new_solution = solve_image(img, camera=new_cal.camera, epoch=epoch, parity="normal")
        if not new_solution.solved:
            break
        grew = len(new_solution.matches) > len(frame)
        cal, solution, frame = new_cal, new_solution, CalibrationFrame.from_solution(new_solution)
        if not grew:
            break
    if cal is None:
        return SelfCalibration(status=Status.OK, reason="too few stars to calibrate; the first solve is kept",
                               solution=solution, first_solve_rms_arcsec=first_rms)
    final = _calibrated(frame, _camera_of(cal), fit)
    final = final if final.status else cal
    pinhole = _pinhole_on_the_same_stars(frame, final)
    n = int(np.count_nonzero(final.inliers[0]))
    return SelfCalibration(
        status=Status.OK, reason="", solution=solution, calibration=final, pinhole_rms_px=pinhole.rms_px,
        calibrated_rms_px=final.rms_px, pixel_scale_arcsec=_camera_of(final).pixel_scale_arcsec, n_pinhole=n,
        n_calibrated=n, rounds=rounds, first_solve_rms_arcsec=first_rms)
