"""Jacobs 1995's lens model: a tilted CCD plus a cubic radial lens term (Jacobs 1995 §6.2.3, App. F.2.3, App F.1).

A CCD tilted by theta_max about an axis in the focal plane (the tilt is largest in the direction
phi_max) stretches the image on one side and compresses it on the other; the lens adds a radial
term. At a measured point at radius r and azimuth phi from the principal point (pixels; phi from
+x towards +y, our choice for the seed's ambiguous "from +u"), the local tilt is
``theta = asin(sin theta_max cos(phi - phi_max))`` (eq. 6.14) and the true (pinhole) radius is
(eq. 6.13, the correction the thesis applies to centroids)::

    r_a = cos(theta) (r - dr_lens(r)) / (1 + (r / f) sin(theta)),
    dr_lens(r) = f (c1 rho + c2 rho^2 + c3 rho^3),   rho = r / f

(the thesis's k1, k2, k3 in mm, for r in mm, are c1, c2 / f, c3 / f^2). The azimuth is kept. The
forward model (direction -> pixel) inverts this along the radius by Newton's method.

The tilt is parameterised as ``(tilt_x, tilt_y) = theta_max (cos phi_max, sin phi_max)`` (radians)
so that zero tilt is not a singular point of the fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import Camera

TILTED_CCD_PARAMETERS: tuple[str, ...] = ("f", "cx", "cy", "tilt_x", "tilt_y", "c1", "c2", "c3")


@dataclass(frozen=True)
class TiltedCcdCamera:
    """A camera with Jacobs 1995's tilted-CCD + radial lens model.

    Attributes
    ----------
    width, height : int
    f : float
        Focal length, px (square pixels).
    cx, cy : float
        Principal point, our pixel convention.
    tilt_x, tilt_y : float
        ``theta_max * (cos phi_max, sin phi_max)``, radians.
    c1, c2, c3 : float
        Radial lens coefficients (dimensionless, on rho = r / f).
    """

    width: int
    height: int
    f: float
    cx: float
    cy: float
    tilt_x: float = 0.0
    tilt_y: float = 0.0
    c1: float = 0.0
    c2: float = 0.0
    c3: float = 0.0

    @classmethod
    def from_tilt(cls, width: int, height: int, f: float, cx: float, cy: float, theta_max_rad: float,
                  phi_max_rad: float, c1: float = 0.0, c2: float = 0.0, c3: float = 0.0) -> TiltedCcdCamera:
        return cls(width, height, f, cx, cy, theta_max_rad * math.cos(phi_max_rad),
                   theta_max_rad * math.sin(phi_max_rad), c1, c2, c3)

    @property
    def theta_max_rad(self) -> float:
        return math.hypot(self.tilt_x, self.tilt_y)

    @property
    def phi_max_rad(self) -> float:
        return math.atan2(self.tilt_y, self.tilt_x) % (2 * math.pi)

    def _true_radius(self, r: NDArray, phi: NDArray) -> NDArray:
        """eq. 6.13: pinhole radius (px) of a measured radius r at azimuth phi."""
        sin_theta = np.sin(self.theta_max_rad) * np.cos(phi - self.phi_max_rad)
        cos_theta = np.sqrt(1.0 - sin_theta**2)
        rho = r / self.f
        dr = self.f * rho * (self.c1 + rho * (self.c2 + rho * self.c3))
        return cos_theta * (r - dr) / (1.0 + rho * sin_theta)

    def pixel_to_vector(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Unit camera-frame vectors (..., 3) of measured pixel positions."""
        dx, dy = np.asarray(x, float) - self.cx, np.asarray(y, float) - self.cy
        r, phi = np.hypot(dx, dy), np.arctan2(dy, dx)
        r_a = self._true_radius(r, phi)
        v = np.stack([r_a * np.cos(phi) / self.f, r_a * np.sin(phi) / self.f, np.ones_like(r)], axis=-1)
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    def vector_to_pixel(self, vectors: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pixel positions of camera-frame vectors (v_z > 0), by Newton's method on the radius."""
        v = np.asarray(vectors, float)
        a, b = v[..., 0] / v[..., 2], v[..., 1] / v[..., 2]
        r_a, phi = self.f * np.hypot(a, b), np.arctan2(b, a)
        r = r_a.copy()
        for _ in range(30):
            g = self._true_radius(r, phi) - r_a
            dg = (self._true_radius(r + 1e-3, phi) - self._true_radius(r - 1e-3, phi)) / 2e-3
            step = g / dg
            r = r - step
            if np.all(np.abs(step) < 1e-9):
                break
        return self.cx + r * np.cos(phi), self.cy + r * np.sin(phi)


@dataclass(frozen=True)
class TiltedCcdModel:
    """The tilted-CCD model for :func:`startrack.calibrate._stars.calibrate_from_stars`.

    Residuals are taken in the corrected (pinhole) image plane, as the thesis does: the measured
    position corrected by eq. 6.13 minus the pinhole projection of the catalog star, in pixels.
    Parameters (:data:`TILTED_CCD_PARAMETERS`): f (px); cx, cy as offsets from ``base``; tilt_x,
    tilt_y (rad); c1, c2, c3.
    """

    base: Camera
    names: tuple[str, ...] = TILTED_CCD_PARAMETERS

    def initial(self) -> NDArray[np.float64]:
        return np.array([self.base.fx, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    def tilted_camera(self, params: NDArray) -> TiltedCcdCamera:
        f, dcx, dcy, tx, ty, c1, c2, c3 = (float(p) for p in params)
        return TiltedCcdCamera(self.base.width, self.base.height, f, self.base.cx + dcx, self.base.cy + dcy,
                               tx, ty, c1, c2, c3)

    def residuals(self, params: NDArray, vectors_cam: NDArray, x: NDArray, y: NDArray) -> NDArray[np.float64]:
        cam = self.tilted_camera(params)
        corrected = cam.pixel_to_vector(x, y)
        f = cam.f
        meas = np.stack([corrected[:, 0] / corrected[:, 2], corrected[:, 1] / corrected[:, 2]], axis=1)
        pred = np.stack([vectors_cam[:, 0] / vectors_cam[:, 2], vectors_cam[:, 1] / vectors_cam[:, 2]], axis=1)
        return f * (pred - meas)
