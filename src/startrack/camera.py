"""The camera model: intrinsics, Brown-Conrady distortion, pixel <-> unit vector.

Pixels follow :mod:`startrack.conventions` (0-based, pixel centres, (x, y) = (column, row)).
The distortion is the Brown-Conrady model in the form OpenCV and Bouguet's toolbox use (Fowler 2013
Ch. 4 §II.B): with normalised pinhole coordinates (a, b) = (v_x / v_z, v_y / v_z)
and r^2 = a^2 + b^2::

    radial = 1 + k1 r^2 + k2 r^4 + k3 r^6
    a_d = a * radial + 2 p1 a b + p2 (r^2 + 2 a^2)
    b_d = b * radial + p1 (r^2 + 2 b^2) + 2 p2 a b
    x = cx + fx * a_d,    y = cy + fy * b_d

The inverse (pixel -> vector) is solved by Newton's method to 1e-6 px.
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidInputError

UNDISTORT_TOL_PX = 1e-6
UNDISTORT_MAX_ITER = 50


def focal_px_from_fov(size_px: float, fov_rad: float) -> float:
    """Pinhole focal length in pixels that spans ``size_px`` pixels with ``fov_rad``.

    ``f = size / (2 tan(fov / 2))`` (Huffman 2006 §2.3 eq. 2.1). The size is the full width in pixels
    (edge to edge), so ``fov`` is the angle between the outer edges of the outer pixels.
    """
    if not 0.0 < fov_rad < math.pi:
        raise InvalidInputError(f"field of view must be between 0 and 180 deg, got {math.degrees(fov_rad):g} deg")
    return size_px / (2.0 * math.tan(fov_rad / 2.0))


def fov_from_focal_px(size_px: float, focal_px: float) -> float:
    """Field of view in radians spanned by ``size_px`` pixels at focal length ``focal_px``."""
    if focal_px <= 0:
        raise InvalidInputError(f"focal length must be positive, got {focal_px:g} px")
    return 2.0 * math.atan(size_px / (2.0 * focal_px))


def _check_size(key: str, value: object) -> int:
    """``value`` when it is an image side (an integer of at least 2 px), else InvalidInputError naming ``key``."""
    if not (isinstance(value, int | np.integer) and value >= 2):
        raise InvalidInputError(f"camera {key} must be an integer of at least 2 px, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class Camera:
    """A star camera: image size, focal lengths, principal point and lens distortion.

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    fx, fy : float
        Focal lengths in pixels (``fy`` defaults to ``fx``). Their ratio is the pixel aspect,
        :attr:`pixel_aspect` = fx / fy: how many pixel widths one pixel's height spans on the
        sky (1 for square pixels, about 1.9 for a sensor whose rows are 1.9 widths apart).
    cx, cy : float
        Principal point in our pixel convention; defaults to the image centre
        ((width - 1) / 2, (height - 1) / 2).
    k1, k2, k3, p1, p2 : float
        Brown-Conrady radial and tangential coefficients (OpenCV's order is k1, k2, p1, p2, k3).
    name, source : str
        A label and where the numbers come from (a seed section, a calibration).
    pixel_pitch_um : float or None
        Pixel pitch, for radiometry and reporting.
    mirrored : bool
        The image is a mirror image of the sky (a star diagonal, a flipped file): pixel x runs
        against the camera frame's x axis, x = cx - fx a (``docs/conventions.md``, mirror images). The
        camera frame stays right-handed, so an attitude stays a rotation; :meth:`mirror_image`
        gives the camera of the same image flipped left to right.
    """

    width: int
    height: int
    fx: float
    # fy, cx and cy default to None and are always floats once __post_init__ has filled them.
    fy: float = None  # type: ignore[assignment]
    cx: float = None  # type: ignore[assignment]
    cy: float = None  # type: ignore[assignment]
    k1: float = 0.0
    k2: float = 0.0
    k3: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    name: str = ""
    source: str = ""
    pixel_pitch_um: float | None = None
    mirrored: bool = False

    def __post_init__(self) -> None:
        for key in ("width", "height"):
            _check_size(key, getattr(self, key))
        if self.fy is None:
            object.__setattr__(self, "fy", self.fx)
        if self.cx is None:
            object.__setattr__(self, "cx", (self.width - 1) / 2.0)
        if self.cy is None:
            object.__setattr__(self, "cy", (self.height - 1) / 2.0)
        for key in _FLOAT_FIELDS:
            object.__setattr__(self, key, _checked_number(key, getattr(self, key)))
        for key in ("fx", "fy"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"camera focal length {key} must be positive and finite, got {value!r} px")
        for key in ("cx", "cy", "k1", "k2", "k3", "p1", "p2"):
            if not math.isfinite(getattr(self, key)):
                raise InvalidInputError(f"camera parameter {key} must be finite, got {getattr(self, key)!r}")
        if not isinstance(self.mirrored, bool | np.bool_):
            raise InvalidInputError(f"camera mirrored must be True or False, got {self.mirrored!r}")
        object.__setattr__(self, "mirrored", bool(self.mirrored))
        for key in ("name", "source"):
            if not isinstance(getattr(self, key), str):
                raise InvalidInputError(f"camera {key} must be a string, got {getattr(self, key)!r}")
        pitch = self.pixel_pitch_um
        number = isinstance(pitch, int | float | np.number) and not isinstance(pitch, bool)
        if pitch is not None and not (number and math.isfinite(pitch) and pitch > 0):
            raise InvalidInputError(f"camera pixel_pitch_um must be None or a positive number of micrometres, "
                                    f"got {pitch!r}")

    # --- construction -----------------------------------------------------------------------
    @classmethod
    def from_fov(cls, width: int, height: int, fov_deg: float, *, pixel_aspect: float = 1.0, **kwargs) -> Camera:
        """A pinhole camera whose horizontal field of view (edge to edge) is ``fov_deg``, with
        pixels ``pixel_aspect`` times as high as they are wide on the sky (fy = fx / pixel_aspect)."""
        try:
            fov = float(fov_deg)
        except (TypeError, ValueError):
            raise InvalidInputError(f"fov_deg must be a number of degrees, got {fov_deg!r}") from None
        if not 0.0 < fov < 180.0:
            raise InvalidInputError(f"fov_deg must be between 0 and 180 deg, got {fov_deg!r}")
        aspect = _checked_aspect(pixel_aspect)
        fx = focal_px_from_fov(_check_size("width", width), math.radians(fov))
        return cls(width=width, height=height, fx=fx, fy=fx / aspect, **kwargs)

    def with_pixel_aspect(self, pixel_aspect: float) -> Camera:
        """The same camera with fy = fx / ``pixel_aspect`` (fx kept)."""
        return self.with_focal(self.fx, self.fx / _checked_aspect(pixel_aspect))

    def with_focal(self, fx: float, fy: float | None = None) -> Camera:
        """The same camera with other focal lengths (fy keeps the fx / fy ratio if not given)."""
        fx = _checked_number("fx", fx)
        fy = fx * self.fy / self.fx if fy is None else _checked_number("fy", fy)
        if not (fx > 0 and fy > 0 and math.isfinite(fx) and math.isfinite(fy)):
            raise InvalidInputError(f"focal lengths must be positive and finite, got {fx!r}, {fy!r} px")
        return self._updated(fx=float(fx), fy=float(fy))

    def mirror_image(self) -> Camera:
        """The camera of this camera's image flipped left to right (column x to width - 1 - x):
        the principal point reflected, :attr:`mirrored` toggled, everything else kept. Twice is
        the camera itself."""
        new = self._updated(cx=(self.width - 1) - self.cx)
        object.__setattr__(new, "mirrored", not self.mirrored)
        return new

    def with_distortion(self, **coefficients: float) -> Camera:
        """The same camera with other distortion coefficients (k1, k2, k3, p1, p2)."""
        unknown = set(coefficients) - {"k1", "k2", "k3", "p1", "p2"}
        if unknown:
            raise InvalidInputError(f"unknown distortion coefficients {sorted(unknown)}; valid: k1, k2, k3, p1, p2")
        values = {k: _checked_number(k, v) for k, v in coefficients.items()}
        if not all(math.isfinite(v) for v in values.values()):
            raise InvalidInputError(f"distortion coefficients must be finite, got {coefficients}")
        return self._updated(**values)

    def _updated(self, **fields: float) -> Camera:
        """A copy with some already-checked fields changed (cheaper than ``dataclasses.replace``,
        which re-runs every check; refinement loops call this many times)."""
        new = object.__new__(type(self))  # a Camera holds only its fields (no cached values): copy them
        new.__dict__.update(self.__dict__, **fields)
        return new

    # --- derived quantities -----------------------------------------------------------------
    @property
    def fov_deg(self) -> float:
        """Horizontal pinhole field of view, edge to edge, in degrees."""
        return math.degrees(fov_from_focal_px(self.width, self.fx))

    @property
    def fov_height_deg(self) -> float:
        """Vertical pinhole field of view in degrees."""
        return math.degrees(fov_from_focal_px(self.height, self.fy))

    @property
    def fov_long_deg(self) -> float:
        """Pinhole field of view along the image's long side (the larger of :attr:`fov_deg` and
        :attr:`fov_height_deg`) in degrees: how wide a lens is, whichever way the image is held."""
        return max(self.fov_deg, self.fov_height_deg)

    @property
    def fov_diagonal_deg(self) -> float:
        """Diagonal pinhole field of view in degrees (through the principal point, no distortion)."""
        half_w = (self.width / 2.0) / self.fx
        half_h = (self.height / 2.0) / self.fy
        return math.degrees(2.0 * math.atan(math.hypot(half_w, half_h)))

    @property
    def pixel_aspect(self) -> float:
        """fx / fy: a pixel's height on the sky over its width (1 for square pixels)."""
        return self.fx / self.fy

    @property
    def pixel_scale_arcsec(self) -> float:
        """Angular size of one pixel at the principal point, in arcseconds."""
        return math.degrees(1.0 / math.sqrt(self.fx * self.fy)) * 3600.0

    @property
    def x_sign(self) -> float:
        """+1, or -1 for a :attr:`mirrored` image: pixel x = cx + x_sign fx a."""
        return -1.0 if self.mirrored else 1.0

    @property
    def has_distortion(self) -> bool:
        return (self.k1, self.k2, self.k3, self.p1, self.p2) != (0.0, 0.0, 0.0, 0.0, 0.0)

    # --- projection --------------------------------------------------------------------------
    def _distort(self, a: NDArray, b: NDArray) -> tuple[NDArray, NDArray]:
        r2 = a * a + b * b
        radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3))
        ad = a * radial + 2.0 * self.p1 * a * b + self.p2 * (r2 + 2.0 * a * a)
        bd = b * radial + self.p1 * (r2 + 2.0 * b * b) + 2.0 * self.p2 * a * b
        return ad, bd

    def _distort_jacobian(self, a: NDArray, b: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        r2 = a * a + b * b
        radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3))
        dradial = self.k1 + r2 * (2.0 * self.k2 + 3.0 * self.k3 * r2)  # d radial / d r2
        daa = radial + a * dradial * 2 * a + 2 * self.p1 * b + self.p2 * 6.0 * a
        dab = a * dradial * 2 * b + 2 * self.p1 * a + self.p2 * 2.0 * b
        dba = b * dradial * 2 * a + self.p1 * 2.0 * a + 2 * self.p2 * b
        dbb = radial + b * dradial * 2 * b + self.p1 * 6.0 * b + 2 * self.p2 * a
        return daa, dab, dba, dbb

    def vector_to_pixel(self, vectors: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pixel coordinates (x, y) of camera-frame directions.

        Parameters
        ----------
        vectors : array_like, shape (..., 3)
            Directions in the camera frame (need not be unit length).

        Returns
        -------
        x, y : ndarray, shape (...)
            Pixel coordinates; NaN for directions at or behind the image plane (v_z <= 0), and
            for directions beyond the radius where the radial distortion folds back
            (:func:`radial_fold_r2`: past it the polynomial would put them back inside the
            image, on top of the directions nearer the axis). Points outside the image are
            returned as they are; see :meth:`in_image`.
        """
        v = np.asarray(vectors, dtype=float)
        if v.shape[-1:] != (3,):
            raise InvalidInputError(f"vectors must have shape (..., 3), got {v.shape}")
        vz = v[..., 2]
        if np.all(vz > 0):  # the usual case, without the masking below
            inv_z = 1.0 / vz
            a, b = v[..., 0] * inv_z, v[..., 1] * inv_z
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                front = vz > 0
                a = np.where(front, v[..., 0] / np.where(front, vz, 1.0), np.nan)
                b = np.where(front, v[..., 1] / np.where(front, vz, 1.0), np.nan)
        if self.has_distortion:
            a, b = self._beyond_fold_as_nan(*self._distort(a, b), a * a + b * b)
        return self.cx + self.x_sign * self.fx * a, self.cy + self.fy * b

    def _beyond_fold_as_nan(self, ad: NDArray, bd: NDArray, r2: NDArray) -> tuple[NDArray, NDArray]:
        """The distorted (ad, bd), NaN where the pinhole radius squared ``r2`` lies beyond the fold."""
        fold = radial_fold_r2(self.k1, self.k2, self.k3)
        if fold == math.inf:  # a lens that never folds (k1 >= 0, most fitted ones): no comparison
            return ad, bd
        beyond = r2 >= fold
        if not beyond.any():
            return ad, bd
        return np.where(beyond, np.nan, ad), np.where(beyond, np.nan, bd)

    def project_with_jacobian(self, vectors: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """Pixel coordinates of camera-frame vectors (v_z > 0) and their derivatives.

        Parameters
        ----------
        vectors : ndarray, shape (N, 3)

        Returns
        -------
        x, y : ndarray, shape (N,)
        jacobian : ndarray, shape (N, 2, 3)
            d(x, y) / d(vector), pixels per unit of vector component.
        """
        v = np.asarray(vectors, dtype=float)
        inv_z = 1.0 / v[:, 2]
        a, b = v[:, 0] * inv_z, v[:, 1] * inv_z
        zero = np.zeros_like(a)
        da = np.stack([inv_z, zero, -a * inv_z], axis=-1)  # d a / d v
        db = np.stack([zero, inv_z, -b * inv_z], axis=-1)
        fx = self.x_sign * self.fx
        if self.has_distortion:
            daa, dab, dba, dbb = self._distort_jacobian(a, b)
            ad, bd = self._distort(a, b)
            dx = fx * (daa[:, None] * da + dab[:, None] * db)
            dy = self.fy * (dba[:, None] * da + dbb[:, None] * db)
        else:
            ad, bd = a, b
            dx, dy = fx * da, self.fy * db
        return self.cx + fx * ad, self.cy + self.fy * bd, np.stack([dx, dy], axis=1)

    def pixel_to_vector(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Unit camera-frame vectors (..., 3) of pixel coordinates (distortion removed).

        Raises
        ------
        InvalidInputError
            If the coordinates are not finite.
        """
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise InvalidInputError("pixel coordinates must be finite numbers (got NaN or inf)")
        ad = (x - self.cx) / (self.x_sign * self.fx)
        bd = (y - self.cy) / self.fy
        a, b = self._undistort(ad, bd) if self.has_distortion else (ad, bd)
        v = np.stack([a, b, np.ones_like(a)], axis=-1)
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    def _undistort(self, ad: NDArray, bd: NDArray) -> tuple[NDArray, NDArray]:
        """Invert the distortion by Newton's method (vectorised), to 1e-6 px.

        Points where it does not converge (far outside the image, where the polynomial folds
        back) come out as NaN rather than as a wrong direction.
        """
        a, b = ad.copy(), bd.copy()
        tol = UNDISTORT_TOL_PX / max(self.fx, self.fy)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(UNDISTORT_MAX_ITER):
                fa, fb = self._distort(a, b)
                ra, rb = fa - ad, fb - bd
                if np.all(np.hypot(ra, rb) < tol):
                    break
                daa, dab, dba, dbb = self._distort_jacobian(a, b)
                det = daa * dbb - dab * dba
                a = a - (dbb * ra - dab * rb) / det
                b = b - (-dba * ra + daa * rb) / det
            fa, fb = self._distort(a, b)
            bad = ~(np.hypot(fa - ad, fb - bd) < tol)
        return np.where(bad, np.nan, a), np.where(bad, np.nan, b)

    def in_image(self, x: ArrayLike, y: ArrayLike, margin_px: float | NDArray[np.float64] = 0.0) -> NDArray[np.bool_]:
        """True where (x, y) lies inside the image, at least ``margin_px`` (a number, or an array
        broadcasting against x) from its outer edge."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        lo = -0.5 + margin_px
        with np.errstate(invalid="ignore"):
            return (x >= lo) & (y >= lo) & (x <= self.width - 0.5 - margin_px) & (y <= self.height - 0.5 - margin_px)


_FLOAT_FIELDS = ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "p1", "p2")
"""The Camera fields that hold one real number each (checked by :func:`_checked_number`)."""

_FIELD_MEANING = {"fx": "a focal length in pixels", "fy": "a focal length in pixels",
                  "cx": "a principal point column in pixels", "cy": "a principal point row in pixels"}


@functools.lru_cache(maxsize=256)
def radial_fold_r2(k1: float, k2: float, k3: float) -> float:
    """The squared normalised pinhole radius s = r^2 where the radial distortion
    r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing with r (its derivative
    1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3 first reaches zero); inf when it grows for every r.

    Beyond that radius the model folds back: a direction farther from the axis lands nearer the
    centre, on a pixel that also images a direction inside the fold. A barrel lens with
    k1 = -0.1 folds at r = 1.83 (61 deg off axis), so a 90 deg camera would show stars from
    61-90 deg off axis in its corners; :meth:`Camera.vector_to_pixel` gives NaN there instead.
    """
    roots = np.roots([7.0 * k3, 5.0 * k2, 3.0 * k1, 1.0])  # leading zero coefficients are dropped
    real = roots.real[np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots))]
    positive = real[real > 0]
    return float(positive.min()) if positive.size else math.inf


def _checked_number(key: str, value: object) -> float:
    """``value`` as a float if it is one real number (int, float or NumPy scalar, not a bool, a
    string, None or an array); otherwise an InvalidInputError naming the field and what is valid."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_):
        return float(value)
    meaning = _FIELD_MEANING.get(key, "a distortion coefficient (dimensionless)")
    raise InvalidInputError(f"camera {key} must be a real number ({meaning}), got {type(value).__name__} "
                            f"{_short_repr(value)}")


def _short_repr(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _checked_aspect(pixel_aspect: float) -> float:
    try:
        aspect = float(pixel_aspect)
    except (TypeError, ValueError):
        aspect = math.nan
    if not (math.isfinite(aspect) and aspect > 0):
        raise InvalidInputError(f"pixel_aspect must be a positive number (a pixel's height over its width), "
                                f"got {pixel_aspect!r}")
    return aspect


# --- presets from the seeds ------------------------------------------------------------------
def _from_pitch(name: str, width: int, height: int, focal_mm: float, pitch_um: float,
                source: str, pitch_v_um: float | None = None) -> Camera:
    pitch_v = pitch_um if pitch_v_um is None else pitch_v_um
    return Camera(width=width, height=height, fx=focal_mm * 1000.0 / pitch_um,
                  fy=focal_mm * 1000.0 / pitch_v, name=name, source=source, pixel_pitch_um=pitch_um)


PRESETS: dict[str, Camera] = {
    "far-mst": _from_pitch(
        "far-mst", 1280, 1024, 15.97, 6.7,
        "Huffman 2006 Table 7.1 (p.127): FAR-MST simulation camera, IBIS5-A-1300, 30 x 24.25 deg"),
    "sunsat": _from_pitch(
        "sunsat", 752, 582, 25.0, 6.5, pitch_v_um=6.25,
        source="Jacobs 1995 §2.1-2.2: Sunsat star camera CCD, 752 x 582 effective pixels, "
               "6.5 x 6.25 um pitch, 25 mm f/1.4"),
    "aptina-mt9p031": Camera(
        width=2592, height=1944, fx=2745.88, fy=2747.75, cx=1351.9, cy=975.691,
        k1=-0.1755, k2=0.1983, p1=0.0002264, p2=0.0, k3=0.0, pixel_pitch_um=2.2,
        name="aptina-mt9p031",
        source="Fowler 2013 Table 1.3 and Table 4.4 (12.5 mm grid calibration, the one used)"),
    "droid-x2": Camera(
        width=3264, height=2448, fx=3520.75, fy=3521.15, cx=1620.66, cy=1214.52,
        k1=0.1043, k2=-0.4592, pixel_pitch_um=1.4, name="droid-x2",
        source="Fowler 2013 Table 1.2 and Table 4.3 (6 mm grid calibration, the one used)"),
    "starnav-i": _from_pitch(
        "starnav-i", 512, 512, 58.0, 15.84,
        "Samaan 2002 Table 1 / §simulation: StarNav I, 512 x 512, f = 58 mm; pitch 15.84 um gives the "
        "8 deg FOV that Table 1 implies (the text's 7 deg is an erratum: Table 1's rates follow from 8 deg)"),
}


def preset_key(name: str) -> str:
    """The key of :data:`PRESETS` a preset name stands for: case, surrounding blanks and ``_`` for
    ``-`` do not matter (``" Droid_X2"`` is ``"droid-x2"``). InvalidInputError if it is not a string."""
    if not isinstance(name, str):
        raise InvalidInputError(f"a preset name must be a string, got {name!r}")
    return name.strip().lower().replace("_", "-")


def get_preset(name: str) -> Camera:
    """A named camera from the seeds (see :data:`PRESETS` for the names and their sources)."""
    key = preset_key(name)
    if key not in PRESETS:
        raise InvalidInputError(f"unknown camera preset {name!r}; valid presets: {', '.join(sorted(PRESETS))}")
    return PRESETS[key]
