"""Calibration on the bench: checkerboard images -> intrinsics and distortion (Fowler 2013 Ch. 4).

Fowler 2013 calibrated with Bouguet's toolbox (Zhang's method; Fowler 2013 Ch.4 §II.C and §IV); OpenCV's
``calibrateCamera`` is the same method and the same Brown-Conrady model as our
:class:`~startrack.camera.Camera` (OpenCV order k1, k2, p1, p2, k3; pixel centres 0-based like
ours). On top of it, Fowler 2013's practice:

1. **outlier images**: a view whose RMS reprojection error lies beyond the main cluster (median +
   ``reject_sigma`` robust sigmas) is dropped and the calibration repeated;
2. **pruning**: a distortion coefficient whose 3-sigma uncertainty exceeds its value is fixed at
   zero and the calibration repeated (p1 and p2 together: OpenCV fixes the tangential terms as a
   pair);
3. a **report** of the residuals: overall RMS, per-axis standard deviation (the toolbox's "pixel
   error"), per-view RMS, and the 1-sigma uncertainty of every parameter.

OpenCV (``opencv-python-headless``) is imported only when these functions run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ..errors import InvalidInputError

_DIST_FLAGS = {"k1": "CALIB_FIX_K1", "k2": "CALIB_FIX_K2", "k3": "CALIB_FIX_K3", "p": "CALIB_ZERO_TANGENT_DIST"}
_STD_INDEX = {"fx": 0, "fy": 1, "cx": 2, "cy": 3, "k1": 4, "k2": 5, "p1": 6, "p2": 7, "k3": 8}


def _cv2():
    try:
        import cv2
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("bench calibration needs OpenCV: pip install opencv-python-headless") from None
    return cv2


@dataclass(frozen=True)
class Checkerboard:
    """A flat checkerboard: ``columns`` x ``rows`` *inner* corners, squares ``square_mm`` wide."""

    columns: int
    rows: int
    square_mm: float

    def __post_init__(self) -> None:
        if self.columns < 3 or self.rows < 3 or not self.square_mm > 0:
            raise InvalidInputError(f"a checkerboard needs at least 3 x 3 inner corners and a positive square size, "
                                    f"got {self.columns} x {self.rows}, {self.square_mm} mm")

    def object_points(self) -> NDArray[np.float32]:
        """Board coordinates (columns * rows, 3) of the inner corners, mm, row by row."""
        gx, gy = np.meshgrid(np.arange(self.columns), np.arange(self.rows))
        pts = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1) * self.square_mm
        return pts.astype(np.float32)


def find_corners(image: NDArray, board: Checkerboard) -> NDArray[np.float64] | None:
    """Sub-pixel inner-corner positions (columns * rows, 2) in our pixel convention, or None when
    the board is not found. ``image`` is a 2-D array (any numeric type; scaled to 8 bit)."""
    cv2 = _cv2()
    img = np.asarray(image, dtype=float)
    if img.ndim != 2:
        raise InvalidInputError(f"image must be 2-D (one channel), got shape {img.shape}")
    lo, hi = float(np.min(img)), float(np.max(img))
    grey = np.zeros(img.shape, np.uint8) if hi <= lo else np.round(255 * (img - lo) / (hi - lo)).astype(np.uint8)
    found, corners = cv2.findChessboardCorners(grey, (board.columns, board.rows),
                                               flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
    corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1), criteria)
    return corners.reshape(-1, 2).astype(float)


@dataclass(frozen=True)
class BenchCalibration:
    """Result of :func:`calibrate_checkerboard`.

    Attributes
    ----------
    camera : Camera
    sigma : dict
        1-sigma uncertainty of fx, fy, cx, cy (px) and of the distortion coefficients still fitted.
    pruned : tuple of str
        Coefficients fixed at zero by the 3-sigma rule ("p" stands for p1 and p2).
    used_views, rejected_views : tuple of int
        Indices (into the input) of the views kept and of those dropped as outliers.
    rms_px : float
        RMS reprojection distance over all corners of the kept views.
    sigma_xy_px : (float, float)
        Standard deviation of the x and y residuals (the toolbox's "pixel error").
    view_rms_px : ndarray
        RMS per kept view.
    """

    camera: Camera
    sigma: dict[str, float]
    pruned: tuple[str, ...]
    used_views: tuple[int, ...]
    rejected_views: tuple[int, ...]
    rms_px: float
    sigma_xy_px: tuple[float, float]
    view_rms_px: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))


def _run(cv2, obj, img, size, fixed):
    flags = 0
    for name in fixed:
        flags |= getattr(cv2, _DIST_FLAGS[name])
    out = cv2.calibrateCameraExtended(obj, img, size, None, None, flags=flags)
    _, k, dist, rvecs, tvecs, std_intr, _, _ = out
    residuals = [cv2.projectPoints(o, r, t, k, dist)[0].reshape(-1, 2) - i.reshape(-1, 2)
                 for o, i, r, t in zip(obj, img, rvecs, tvecs, strict=True)]
    return k, dist.ravel(), std_intr.ravel(), residuals


def _weakest(dist, std, fixed) -> str | None:
    values = {"k1": dist[0], "k2": dist[1], "k3": dist[4] if dist.size > 4 else 0.0}
    ratios = {}
    for name, value in values.items():
        s = std[_STD_INDEX[name]]
        if name not in fixed and 3 * s > abs(value):
            ratios[name] = 3 * s / max(abs(value), 1e-300)
    if "p" not in fixed and all(3 * std[_STD_INDEX[q]] > abs(dist[i]) for q, i in (("p1", 2), ("p2", 3))):
        ratios["p"] = min(3 * std[6] / max(abs(dist[2]), 1e-300), 3 * std[7] / max(abs(dist[3]), 1e-300))
    return max(ratios, key=lambda k: ratios[k]) if ratios else None


def _outlier_views(view_rms: NDArray, reject_sigma: float) -> NDArray[np.bool_]:
    med = np.median(view_rms)
    spread = 1.4826 * np.median(np.abs(view_rms - med))
    return view_rms > med + reject_sigma * max(spread, 0.05 * med)


def calibrate_checkerboard(corners: list[NDArray | None], board: Checkerboard, width: int, height: int, *,
                           prune: bool = True, reject_sigma: float = 3.0, min_views: int = 3) -> BenchCalibration:
    """Intrinsics and distortion from checkerboard corners (one array per image, None if not found).

    Parameters
    ----------
    corners : list of ndarray (columns * rows, 2) or None
        From :func:`find_corners`, our pixel convention.
    board : Checkerboard
    width, height : int
        Image size, px.
    prune, reject_sigma, min_views
        The 3-sigma rule on/off; the outlier-view limit in robust sigmas of the per-view RMS; the
        fewest views to calibrate from.
    """
    cv2 = _cv2()
    views = [i for i, c in enumerate(corners) if c is not None]
    if len(views) < min_views:
        raise InvalidInputError(f"need at least {min_views} images with the board found, got {len(views)}")
    obj_all = board.object_points()
    fixed: list[str] = []
    rejected: list[int] = []
    while True:
        obj = [obj_all for _ in views]
        img = [np.asarray(corners[i], np.float32).reshape(-1, 1, 2) for i in views]
        k, dist, std, residuals = _run(cv2, obj, img, (width, height), fixed)
        view_rms = np.array([np.sqrt(np.mean(np.sum(r**2, axis=1))) for r in residuals])
        bad = _outlier_views(view_rms, reject_sigma)
        if np.any(bad) and len(views) - np.count_nonzero(bad) >= min_views:
            rejected += [v for v, b in zip(views, bad, strict=True) if b]
            views = [v for v, b in zip(views, bad, strict=True) if not b]
            continue
        weakest = _weakest(dist, std, fixed) if prune else None
        if weakest is None:
            break
        fixed.append(weakest)
    return _bench_result(k, dist, std, fixed, views, rejected, residuals, view_rms, width, height)


def _bench_result(k, dist, std, fixed, views, rejected, residuals, view_rms, width, height) -> BenchCalibration:
    k3 = dist[4] if dist.size > 4 else 0.0
    camera = Camera(width=width, height=height, fx=k[0, 0], fy=k[1, 1], cx=k[0, 2], cy=k[1, 2], k1=dist[0],
                    k2=dist[1], p1=dist[2], p2=dist[3], k3=k3, name="bench", source="checkerboard (OpenCV)")
    free = [n for n in _STD_INDEX if not (n in fixed or (n in ("p1", "p2") and "p" in fixed))]
    all_res = np.concatenate(residuals)
    return BenchCalibration(
        camera=camera, sigma={n: float(std[_STD_INDEX[n]]) for n in free}, pruned=tuple(fixed),
        used_views=tuple(views), rejected_views=tuple(rejected),
        rms_px=float(np.sqrt(np.mean(np.sum(all_res**2, axis=1)))),
        sigma_xy_px=(float(np.std(all_res[:, 0])), float(np.std(all_res[:, 1]))), view_rms_px=view_rms)


def render_checkerboard(camera: Camera, board: Checkerboard, rot_cam_from_board, board_origin_cam_mm,
                        supersample: int = 3) -> NDArray[np.float64]:
    """A synthetic image (height, width) of the board seen by ``camera`` (distortion included),
    white squares 1, black 0, with a one-square white border; for tests and demonstrations.

    ``rot_cam_from_board`` (a scipy Rotation) and ``board_origin_cam_mm`` (3,) place the board's
    first inner corner in the camera frame.
    """
    s = supersample
    xs = (np.arange(camera.width * s) + 0.5) / s - 0.5
    ys = (np.arange(camera.height * s) + 0.5) / s - 0.5
    gx, gy = np.meshgrid(xs, ys)
    rays = camera.pixel_to_vector(gx.ravel(), gy.ravel())
    normal = rot_cam_from_board.apply([0.0, 0.0, 1.0])
    origin = np.asarray(board_origin_cam_mm, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (origin @ normal) / (rays @ normal)
        hit = rot_cam_from_board.inv().apply(rays * t[:, None] - origin) / board.square_mm
    u, v = hit[:, 0], hit[:, 1]
    inside = (u > -2) & (u < board.columns + 1) & (v > -2) & (v < board.rows + 1) & (t > 0)
    on_board = (u > -1) & (u < board.columns) & (v > -1) & (v < board.rows)
    dark = on_board & ((np.floor(u) + np.floor(v)) % 2 == 0)
    value = np.where(inside & ~dark, 1.0, np.where(inside, 0.0, 0.5))
    return value.reshape(camera.height, s, camera.width, s).mean(axis=(1, 3))
