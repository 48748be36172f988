"""Lens models as parameter vectors, for the joint calibration fit (:mod:`._stars`).

A model turns a vector of intrinsic parameters into per-star residuals in pixels, given the
camera-frame directions of the catalog stars and the measured positions. Every parameter is written
as an *offset from its null value* (principal point from the initial one, distortion from zero,
pixel aspect as ln(fy / fx) from the initial ratio), so that Fowler 2013's pruning rule ("fix a
coefficient to zero when its 3-sigma uncertainty exceeds it", Fowler 2013 Ch.4 §II.C and §IV) applies
to every parameter but the focal length.

- :class:`BrownConradyModel`: the :class:`startrack.camera.Camera` model (OpenCV form; Fowler 2013
  §4.2); residual = projected catalog star - measured position.
- The tilted-CCD + cubic radial model of Jacobs 1995 is in :mod:`._tilted_ccd`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera

BROWN_CONRADY_PARAMETERS: tuple[str, ...] = ("f", "aspect", "cx", "cy", "k1", "k2", "k3", "p1", "p2")
"""f: fx in px; aspect: ln(fy / fx) change; cx, cy: principal point shift in px; k1..p2: distortion."""


@dataclass(frozen=True)
class BrownConradyModel:
    """The Camera's Brown-Conrady model about a starting camera ``base``."""

    base: Camera
    names: tuple[str, ...] = BROWN_CONRADY_PARAMETERS

    def initial(self) -> NDArray[np.float64]:
        """Parameter vector of ``base`` (offsets are zero; distortion as it is)."""
        b = self.base
        return np.array([b.fx, 0.0, 0.0, 0.0, b.k1, b.k2, b.k3, b.p1, b.p2])

    def camera(self, params: NDArray) -> Camera:
        """The camera of a full parameter vector."""
        b = self.base
        f, aspect, dcx, dcy, k1, k2, k3, p1, p2 = (float(v) for v in params)
        fy = f * (b.fy / b.fx) * math.exp(aspect)
        return Camera(width=b.width, height=b.height, fx=f, fy=fy, cx=b.cx + dcx, cy=b.cy + dcy, k1=k1, k2=k2,
                      k3=k3, p1=p1, p2=p2, name=b.name, source=b.source, pixel_pitch_um=b.pixel_pitch_um)

    def residuals(self, params: NDArray, vectors_cam: NDArray, x: NDArray, y: NDArray) -> NDArray[np.float64]:
        """(N, 2) projected minus measured pixel positions."""
        px, py = self.camera(params).vector_to_pixel(vectors_cam)
        return np.stack([px - x, py - y], axis=1)


    def jacobian(self, params: NDArray, vectors_cam: NDArray) -> tuple[NDArray, NDArray]:
        """Derivatives of the residuals: (N, 2, 9) by the parameters and (N, 2, 3) by the
        camera-frame vector (analytic; see :meth:`startrack.camera.Camera.project_with_jacobian`)."""
        cam = self.camera(params)
        v = np.asarray(vectors_cam, float)
        px, py, jac_v = cam.project_with_jacobian(v)
        a, b = v[:, 0] / v[:, 2], v[:, 1] / v[:, 2]
        r2 = a * a + b * b
        ad, bd = (px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy
        one, zero = np.ones_like(a), np.zeros_like(a)
        cols_x = [ad, zero, one, zero, cam.fx * a * r2, cam.fx * a * r2**2, cam.fx * a * r2**3,
                  cam.fx * 2 * a * b, cam.fx * (r2 + 2 * a * a)]
        cols_y = [cam.fy / cam.fx * bd, cam.fy * bd, zero, one, cam.fy * b * r2, cam.fy * b * r2**2,
                  cam.fy * b * r2**3, cam.fy * (r2 + 2 * b * b), cam.fy * 2 * a * b]
        return np.stack([np.stack(cols_x, -1), np.stack(cols_y, -1)], axis=1), jac_v


def distortion_field_px(camera: Camera, n: int = 25) -> tuple[NDArray, NDArray, NDArray]:
    """Lens displacement over an n x n grid of the image: measured minus pinhole pixel position.

    Returns the grid (x, y) and the displacement (n*n, 2) in pixels. Two cameras' fields can be
    compared point by point (the "distortion over the frame" of a calibration).
    """
    gx, gy = np.meshgrid(np.linspace(0, camera.width - 1, n), np.linspace(0, camera.height - 1, n))
    x, y = gx.ravel(), gy.ravel()
    v = camera.pixel_to_vector(x, y)
    pin_x = camera.cx + camera.fx * v[:, 0] / v[:, 2]
    pin_y = camera.cy + camera.fy * v[:, 1] / v[:, 2]
    return x, y, np.stack([x - pin_x, y - pin_y], axis=1)
