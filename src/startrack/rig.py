"""Camera rigs: several star-camera heads (or the two fields of a split-FOV camera) on one body.

A :class:`CameraRig` is a tuple of named :class:`RigHead` s. Each head has a
:class:`~startrack.camera.Camera` and its mounting ``rot_cam_from_body`` (DESIGN.md §3: it maps
body-frame vectors into the head's camera frame, so ``rot_cam_from_icrs = rot_cam_from_body *
rot_body_from_icrs``). A split field of view (Samaan 2002 Eq. 4–5, StarNav II: two orthogonal fields
superimposed on one detector, told apart by deliberate astigmatism) is two heads that name the
same ``detector``: each keeps its own mounting and camera model and has a :class:`PsfShape`, the
elongated PSF that tags its stars.

A rig is saved as JSON (:meth:`CameraRig.save`, :meth:`CameraRig.load`)::

    {"reference": "a",
     "heads": [{"name": "a", "camera": {"width": 1024, "height": 1024, "fx": 3889.0, ...},
                "rot_cam_from_body": {"qx": 0, "qy": 0, "qz": 0, "qw": 1},
                "centroid_sigma_px": 0.2,
                "exclusion": {"sun_deg": 30, "earth_limb_deg": 20, "moon_deg": 10}},
               {"name": "b", "camera": "starnav-i", "rot_cam_from_body": {...},
                "detector": "split", "psf": {"sigma_major_px": 2.0, "sigma_minor_px": 1.0,
                                             "angle_deg": 90}}]}

``camera`` is the camera profile (the fields of :class:`Camera`, as ``startrack calibrate --out``
writes them), a preset name, or the path of such a profile (relative to the rig file).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from .camera import PRESETS, Camera, get_preset, preset_key
from .errors import InvalidInputError, is_real_number

ROTATION_TOLERANCE = 1e-6
"""A mounting given as a quaternion or a matrix must be a rotation to this tolerance (unit norm;
orthonormal with determinant +1)."""


@dataclass(frozen=True)
class PsfShape:
    """An elliptical Gaussian PSF: the astigmatism that tags the stars of one field (Samaan 2002 Eq. 4–5).

    Attributes
    ----------
    sigma_major_px, sigma_minor_px : float
        Standard deviations along the long and the short axis, px (major >= minor > 0).
    angle_deg : float
        Direction of the long axis in the image, from +x towards +y, degrees (taken modulo 180).
    """

    sigma_major_px: float
    sigma_minor_px: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        major, minor, angle = (float(v) for v in (self.sigma_major_px, self.sigma_minor_px, self.angle_deg))
        if not (math.isfinite(major) and math.isfinite(minor) and 0.0 < minor <= major):
            raise InvalidInputError(f"PSF sigmas must be finite with sigma_major_px >= sigma_minor_px > 0, got "
                                    f"{self.sigma_major_px!r} and {self.sigma_minor_px!r}")
        if not math.isfinite(angle):
            raise InvalidInputError(f"PSF angle_deg must be finite, got {self.angle_deg!r}")
        for name, value in (("sigma_major_px", major), ("sigma_minor_px", minor), ("angle_deg", angle % 180.0)):
            object.__setattr__(self, name, value)

    @property
    def elongation(self) -> float:
        """Ratio of the long to the short sigma (1 for a round PSF)."""
        return self.sigma_major_px / self.sigma_minor_px


@dataclass(frozen=True)
class Exclusion:
    """Half-angles (deg) of the cones around the boresight that the Sun, the Earth's limb and the
    Moon must stay out of for the head to see stars (its baffle; Jacobs 1995 §7.6 gives 28.1 deg).
    An angle is measured from the boresight to the body's nearest edge."""

    sun_deg: float = 30.0
    earth_limb_deg: float = 20.0
    moon_deg: float = 10.0

    def __post_init__(self) -> None:
        for name in ("sun_deg", "earth_limb_deg", "moon_deg"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and 0.0 <= value <= 180.0):
                raise InvalidInputError(f"exclusion {name} must be 0 to 180 deg, got {getattr(self, name)!r}")
            object.__setattr__(self, name, value)


def as_rotation(value: Any, what: str) -> Rotation:
    """A single scipy Rotation from a Rotation, a unit quaternion (qx, qy, qz, qw) or a rotation
    matrix (3, 3); anything else raises InvalidInputError naming ``what``."""
    if isinstance(value, Rotation):
        if not value.single:
            raise InvalidInputError(f"{what} must be a single rotation, not a stack of {len(value)}")
        return value
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} is not a rotation: give a scipy Rotation, a unit quaternion "
                                f"(qx, qy, qz, qw) or a 3 x 3 rotation matrix, got {type(value).__name__}") from None
    if array.shape == (4,) and np.all(np.isfinite(array)):
        norm = float(np.linalg.norm(array))
        if abs(norm - 1.0) > ROTATION_TOLERANCE:
            raise InvalidInputError(f"{what} is not a rotation: its quaternion has norm {norm:.6g} (must be 1)")
        return Rotation.from_quat(array)
    if array.shape == (3, 3) and np.all(np.isfinite(array)):
        error = float(np.max(np.abs(array @ array.T - np.eye(3))))
        if error > ROTATION_TOLERANCE or np.linalg.det(array) <= 0.0:
            raise InvalidInputError(f"{what} is not a rotation: the matrix is not orthonormal with determinant +1 "
                                    f"(|M M^T - I| = {error:.3g}, det = {np.linalg.det(array):.6g})")
        return Rotation.from_matrix(array)
    raise InvalidInputError(f"{what} is not a rotation: give a scipy Rotation, a unit quaternion (qx, qy, qz, qw) "
                            f"or a 3 x 3 rotation matrix, got an array of shape {array.shape}")


@dataclass(frozen=True)
class RigHead:
    """One camera head (or one field of a split-FOV camera) of a rig.

    Parameters
    ----------
    name : str
        Unique within the rig; letters, digits, ``-``, ``_`` and ``.`` (it names files and CLI
        arguments ``HEAD=FILE``).
    camera : Camera
    rot_cam_from_body : Rotation
        The mounting: maps body-frame vectors into this head's camera frame. A unit quaternion
        (qx, qy, qz, qw) or a rotation matrix is converted; anything else is refused.
    centroid_sigma_px : float
        Prior 1-sigma centroid noise per axis (px), used until the head's own residuals measure it.
    detector : str or None
        Heads that name the same detector share one image (a split field of view); None: the head
        has its own detector.
    psf : PsfShape or None
        The field's astigmatic PSF (required for the fields of a shared detector).
    exclusion : Exclusion
        Sun, Earth-limb and Moon exclusion angles of this head.
    """

    name: str
    camera: Camera
    rot_cam_from_body: Rotation
    centroid_sigma_px: float = 0.2
    detector: str | None = None
    psf: PsfShape | None = None
    exclusion: Exclusion = dataclasses.field(default_factory=Exclusion)

    def __post_init__(self) -> None:
        _check_name(self.name, "head name")
        label = f"head {self.name!r}"
        if not isinstance(self.camera, Camera):
            raise InvalidInputError(f"{label}: camera must be a startrack Camera, got {type(self.camera).__name__}")
        object.__setattr__(self, "rot_cam_from_body", as_rotation(self.rot_cam_from_body,
                                                                  f"{label}: rot_cam_from_body"))
        sigma = self.centroid_sigma_px
        if not (is_real_number(sigma) and math.isfinite(sigma) and sigma > 0.0):
            raise InvalidInputError(f"{label}: centroid_sigma_px must be a positive number of px, got "
                                    f"{self.centroid_sigma_px!r}")
        object.__setattr__(self, "centroid_sigma_px", float(sigma))
        if self.detector is not None:
            _check_name(self.detector, f"{label}: detector")
        if self.psf is not None and not isinstance(self.psf, PsfShape):
            raise InvalidInputError(f"{label}: psf must be a PsfShape or None")
        if not isinstance(self.exclusion, Exclusion):
            raise InvalidInputError(f"{label}: exclusion must be an Exclusion")

    @property
    def detector_name(self) -> str:
        """The detector this head's stars are read from (its own name when it has its own)."""
        return self.detector if self.detector is not None else self.name

    @property
    def field_psf(self) -> PsfShape:
        """The PSF of a field of a shared detector (InvalidInputError if the head has none)."""
        if self.psf is None:
            raise InvalidInputError(f"head {self.name!r} has no psf; the fields of a shared detector need one")
        return self.psf

    @property
    def boresight_body(self) -> np.ndarray:
        """The head's +z axis in body-frame components, shape (3,)."""
        return self.rot_cam_from_body.inv().apply([0.0, 0.0, 1.0])

    def rot_cam_from_icrs(self, rot_body_from_icrs: Rotation) -> Rotation:
        """This head's attitude for a body attitude."""
        return self.rot_cam_from_body * rot_body_from_icrs


def _check_name(name: Any, what: str) -> None:
    if not (isinstance(name, str) and name and all(c.isalnum() or c in "-_." for c in name)):
        raise InvalidInputError(f"{what} must be a non-empty string of letters, digits, '-', '_' or '.', "
                                f"got {name!r}")


class CameraRig:
    """Named camera heads on one body (module docstring).

    Parameters
    ----------
    heads : sequence of RigHead
        At least one; names unique.
    reference : str, optional
        The head the mounting calibration measures the others against (default the first).

    Raises
    ------
    InvalidInputError
        Two heads with the same name, a detector named like a head it does not hold, the fields of
        a shared detector of different sizes or without a PSF shape, an unknown reference.
    """

    def __init__(self, heads: Sequence[RigHead], reference: str | None = None):
        heads = tuple(heads)
        if not heads or not all(isinstance(h, RigHead) for h in heads):
            raise InvalidInputError("a rig needs at least one head, each a RigHead")
        seen: set[str] = set()
        for head in heads:
            if head.name in seen:
                raise InvalidInputError(f"two heads are named {head.name!r}: head names must be unique")
            seen.add(head.name)
        self.heads = heads
        self._by_name = {h.name: h for h in heads}
        self.reference = heads[0].name if reference is None else reference
        if not isinstance(self.reference, str) or self.reference not in self._by_name:
            raise InvalidInputError(f"reference head {self.reference!r} is not in the rig "
                                    f"(heads: {', '.join(self.names)})")
        self._detectors = self._group_detectors()

    def _group_detectors(self) -> dict[str, tuple[RigHead, ...]]:
        groups: dict[str, list[RigHead]] = {}
        for head in self.heads:
            groups.setdefault(head.detector_name, []).append(head)
        for det, members in groups.items():
            if det in self._by_name and self._by_name[det] not in members:
                raise InvalidInputError(f"detector {det!r} has the name of head {det!r}, which reads another "
                                        "detector: name the detector differently")
            if len(members) > 1:
                _check_shared(det, members)
        return {k: tuple(v) for k, v in groups.items()}

    # --- access --------------------------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(h.name for h in self.heads)

    def head(self, name: str) -> RigHead:
        """The head called ``name``; InvalidInputError listing the heads otherwise."""
        if name not in self._by_name:
            raise InvalidInputError(f"no head named {name!r} in the rig (heads: {', '.join(self.names)})")
        return self._by_name[name]

    def __iter__(self) -> Iterator[RigHead]:
        return iter(self.heads)

    def __len__(self) -> int:
        return len(self.heads)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    @property
    def detectors(self) -> dict[str, tuple[RigHead, ...]]:
        """Each detector's heads (one, or the fields of a split field of view)."""
        return dict(self._detectors)

    def split_detectors(self) -> dict[str, tuple[RigHead, ...]]:
        """The detectors shared by several fields."""
        return {k: v for k, v in self._detectors.items() if len(v) > 1}

    def __repr__(self) -> str:
        return f"CameraRig(heads={list(self.names)}, reference={self.reference!r})"

    # --- JSON ----------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The rig as plain JSON values (see the module docstring)."""
        return {"reference": self.reference, "heads": [_head_to_dict(h) for h in self.heads]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base_dir: str | os.PathLike | None = None) -> CameraRig:
        """A rig from :meth:`to_dict`'s form; camera profile paths are relative to ``base_dir``."""
        if not isinstance(data, Mapping) or not isinstance(data.get("heads"), list):
            raise InvalidInputError("a rig file must be a JSON object with a list 'heads'")
        unknown = set(data) - {"heads", "reference"}
        if unknown:
            raise InvalidInputError(f"unknown rig keys {sorted(unknown)}; valid: heads, reference")
        base = Path(base_dir) if base_dir is not None else Path.cwd()
        heads = [_head_from_dict(entry, k, base) for k, entry in enumerate(data["heads"])]
        return cls(heads, reference=data.get("reference"))

    def save(self, path: str | os.PathLike) -> Path:
        """Write the rig as JSON (atomically) and return the path."""
        from .io import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        return path

    @classmethod
    def load(cls, path: str | os.PathLike) -> CameraRig:
        """Read a rig JSON file; InvalidInputError naming the file and the problem."""
        path = Path(path)
        data = _read_json(path, "rig file")
        try:
            return cls.from_dict(data, base_dir=path.parent)
        except InvalidInputError as exc:
            raise InvalidInputError(f"rig file {path}: {exc}") from None


def _check_shared(detector: str, members: list[RigHead]) -> None:
    """The fields of one detector: same image size, each with its PSF shape."""
    sizes = {(h.camera.width, h.camera.height) for h in members}
    if len(sizes) > 1:
        raise InvalidInputError(f"the fields of detector {detector!r} ({', '.join(h.name for h in members)}) "
                                f"must have one image size, got {sorted(sizes)}")
    missing = [h.name for h in members if h.psf is None]
    if missing:
        raise InvalidInputError(f"the fields of detector {detector!r} are told apart by their PSF shape: "
                                f"give head(s) {', '.join(map(repr, missing))} a psf")


def _plain(value: Any) -> Any:
    return float(value) if isinstance(value, float | np.floating) else value


def camera_to_dict(camera: Camera) -> dict[str, Any]:
    """A camera profile: the Camera's fields as plain JSON values."""
    return {k: _plain(v) for k, v in dataclasses.asdict(camera).items()}


def _head_to_dict(head: RigHead) -> dict[str, Any]:
    qx, qy, qz, qw = (float(v) for v in head.rot_cam_from_body.as_quat(canonical=True))
    out: dict[str, Any] = {"name": head.name, "camera": camera_to_dict(head.camera),
                           "rot_cam_from_body": {"qx": qx, "qy": qy, "qz": qz, "qw": qw},
                           "centroid_sigma_px": head.centroid_sigma_px,
                           "exclusion": dataclasses.asdict(head.exclusion)}
    if head.detector is not None:
        out["detector"] = head.detector
    if head.psf is not None:
        out["psf"] = dataclasses.asdict(head.psf)
    return out


HEAD_KEYS = {"name", "camera", "rot_cam_from_body", "centroid_sigma_px", "detector", "psf", "exclusion"}

MAX_SIDE_PX = 2**31 - 1
"""Largest image side a rig camera may have, px (PNG's limit, a signed 32-bit integer). Beyond it a
size can be no image at all; a smaller one is still checked against the pixel limit of the command
that renders it (``--max-pixels``, :mod:`startrack.io._limits`)."""


def _head_from_dict(entry: Any, index: int, base: Path) -> RigHead:
    if not isinstance(entry, Mapping):
        raise InvalidInputError(f"heads[{index}] must be an object")
    label = f"head {entry.get('name', index)!r}"
    unknown = set(entry) - HEAD_KEYS
    if unknown:
        raise InvalidInputError(f"{label}: unknown keys {sorted(unknown)}; valid: {', '.join(sorted(HEAD_KEYS))}")
    for key in ("name", "camera", "rot_cam_from_body"):
        if key not in entry:
            raise InvalidInputError(f"{label}: missing {key!r}")
    quat = entry["rot_cam_from_body"]
    if not (isinstance(quat, Mapping) and set(quat) == {"qx", "qy", "qz", "qw"}):
        raise InvalidInputError(f"{label}: rot_cam_from_body must be an object with qx, qy, qz, qw (scalar last)")
    values = [_json_number(quat[k], f"{label}: rot_cam_from_body {k}") for k in ("qx", "qy", "qz", "qw")]
    psf_fields = None if entry.get("psf") is None else _numbers_object(entry["psf"], "psf", label, PsfShape)
    exclusion_fields = _numbers_object(entry.get("exclusion", {}), "exclusion", label, Exclusion)
    try:
        psf = None if psf_fields is None else PsfShape(**psf_fields)
        exclusion = Exclusion(**exclusion_fields)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{label}: {exc}") from None
    return RigHead(name=entry["name"], camera=_camera_from(entry["camera"], label, base),
                   rot_cam_from_body=as_rotation(np.array(values), f"{label}: rot_cam_from_body"),
                   centroid_sigma_px=entry.get("centroid_sigma_px", 0.2), detector=entry.get("detector"),
                   psf=psf, exclusion=exclusion)


def _short(value: Any) -> str:
    """``repr(value)`` cut to 60 characters (a JSON value may be a long list or string)."""
    try:
        text = repr(value)
    except ValueError:  # an integer of more digits than Python prints
        return "an integer too long to print"
    return text if len(text) <= 60 else text[:57] + "..."


def _json_number(value: Any, what: str) -> float:
    """``value`` as a float when it is one finite JSON number (not a bool, a string or null); else
    InvalidInputError naming ``what`` (the JSON key as the file writes it)."""
    if is_real_number(value):
        try:
            number = float(value)
        except OverflowError:  # an integer beyond float64
            number = math.inf
        if math.isfinite(number):
            return number
        raise InvalidInputError(f"{what} must be a finite number, got {_short(value)}")
    raise InvalidInputError(f"{what} must be a number, got {_short(value)}")


def _numbers_object(value: Any, key: str, label: str, cls: type) -> dict[str, float]:
    """The fields of the JSON object ``key`` (a :class:`PsfShape` or an :class:`Exclusion`, ``cls``):
    an object of numbers with the dataclass's field names, its required ones present.

    Raises
    ------
    InvalidInputError
        Naming the head, the key (and the field) and what is valid.
    """
    fields = dataclasses.fields(cls)
    names = [f.name for f in fields]
    if not isinstance(value, Mapping):
        raise InvalidInputError(f"{label}: {key} must be an object with {', '.join(names)}, got {_short(value)}")
    unknown = sorted(set(value) - set(names))
    if unknown:
        raise InvalidInputError(f"{label}: unknown {key} keys {unknown}; valid: {', '.join(names)}")
    missing = [f.name for f in fields if f.default is dataclasses.MISSING and f.name not in value]
    if missing:
        raise InvalidInputError(f"{label}: {key} is missing {', '.join(missing)}; valid: {', '.join(names)}")
    return {k: _json_number(v, f"{label}: {key} {k}") for k, v in value.items()}


def _check_side(value: Any, key: str, label: str) -> None:
    """Refuse a camera ``width`` or ``height`` that is not a JSON integer of 2 to :data:`MAX_SIDE_PX` px."""
    if is_real_number(value) and isinstance(value, int | np.integer):
        if 2 <= value <= MAX_SIDE_PX:
            return
        problem = f"is {_short(value)} px, " + ("below 2 px" if value < 2 else "beyond the largest image side")
    elif isinstance(value, float) and value.is_integer():
        beyond = " and beyond the largest image side" if abs(value) > MAX_SIDE_PX else ""
        problem = f"is {value!r}, a decimal number, not a JSON integer{beyond}"
    elif isinstance(value, float):
        problem = f"is {value!r}, not a whole number of pixels"
    else:
        problem = f"is {_short(value)}, not a number"
    raise InvalidInputError(f"{label}: camera {key} {problem}; valid: a JSON integer (no decimal point or "
                            f"exponent) from 2 to {MAX_SIDE_PX:,} px")


def _read_json(path: Path, what: str) -> Any:
    """:func:`startrack.io.read_json_file` (imported when a file is read)."""
    from .io import read_json_file

    return read_json_file(path, what)


def _camera_from(value: Any, label: str, base: Path) -> Camera:
    """A camera from its profile (fields), a preset name or a profile file."""
    if isinstance(value, str):
        if preset_key(value) in PRESETS:
            return get_preset(value)
        path = Path(value) if Path(value).is_absolute() else base / value
        try:
            value = _read_json(path, "camera file")
        except InvalidInputError as exc:
            raise InvalidInputError(f"{label}: camera {value!r} is neither a preset ({', '.join(sorted(PRESETS))}) "
                                    f"nor a readable camera JSON file ({exc})") from None
    if not isinstance(value, Mapping):
        raise InvalidInputError(f"{label}: camera must be a camera profile object, a preset or a file path")
    fields = dataclasses.fields(Camera)
    names = sorted(f.name for f in fields)
    unknown = set(value) - set(names)
    if unknown:
        raise InvalidInputError(f"{label}: unknown camera keys {sorted(unknown)}; valid: {', '.join(names)}")
    missing = [f.name for f in fields if f.default is dataclasses.MISSING and f.name not in value]
    if missing:
        raise InvalidInputError(f"{label}: camera is missing {', '.join(missing)}; a camera profile needs width and "
                                f"height (integers, px) and fx (focal length, px); valid keys: {', '.join(names)}")
    for key in ("width", "height"):
        _check_side(value[key], key, label)
    try:
        return Camera(**value)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{label}: {exc}") from None


__all__ = ["CameraRig", "Exclusion", "PsfShape", "RigHead", "as_rotation", "camera_to_dict"]
