"""Result sets from image files: read, detect, solve, one :class:`ImageRecord` per file; and the
way back from a record to its pixels and to the options it was solved with (for the analyses
that re-run detection).

``solve_options`` (a mapping, as the CLI and the browser tool build it):

- ``fov_deg`` (float) or ``fov_range_deg`` (low, high) or ``camera`` (a preset name or a
  :class:`~startrack.camera.Camera`): the field of view, as in :func:`startrack.solve_image`;
- ``method`` (the matcher), ``epoch`` (a Julian year, used when the file has no time), ``channel``
  ("r", "g", "b" or None), ``utc_offset_hours`` (for EXIF times without a zone);
- ``site`` (a saved site name or a :class:`~startrack.calibrate._sites.Site`), kept in each record;
- ``detector``: a :class:`~startrack.detect.StarDetector` or a mapping of its settings; a
  setting may also be given at the top level (``{"sigma": 4}``).

A file that cannot be read, or whose content the detector refuses, becomes a record whose solution
has status ``TOO_FEW_STARS`` (no stars could be had from it) and a reason starting "unreadable
image:"; it does not stop the others. Bad options raise before any file is read.

``settings`` of each record: ``fov_deg``, ``fov_range_deg``, ``camera`` (its name), ``method``,
``channel``, ``epoch_jyear`` (of the catalog used), ``detector`` (the settings that differ from
the defaults). Pixels are kept in ``record.image`` while the set holds at most
:data:`KEEP_PIXELS_MAX` pixels in all; beyond that only ``record.path`` is kept and the pixels
are read again when an analysis needs them.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ...calibrate import Site, get_site, time_from_header
from ...camera import Camera, get_preset
from ...catalog import jyear_tdb
from ...detect import StarDetector
from ...errors import ImageReadError, InvalidInputError
from ...io import IMAGE_SUFFIXES, Image, in_name_order, read_image
from ...results import AttitudeSolution, Status
from ...solve import check_fov_deg, epoch_jyear, solve_image
from .._records import ImageRecord
from ._core import ResultSet

KEEP_PIXELS_MAX = 64_000_000
"""Pixels of a set kept in memory (about 128 MB of 16-bit images); the rest are re-read."""
UNREADABLE = "unreadable image: "
"""How the reason of a record whose image could not be read (or was refused) begins."""
_OPTION_KEYS = ("fov_deg", "fov_range_deg", "camera", "method", "epoch", "channel", "utc_offset_hours",
                "site", "detector")
_DETECTOR_FIELDS = tuple(f.name for f in fields(StarDetector))


@dataclass(frozen=True)
class SolveOptions:
    """Checked ``solve_options``: what :func:`startrack.solve_image` gets, and the rest."""

    fov_deg: float | None = None
    fov_range_deg: tuple[float, float] | None = None
    camera: Camera | None = None
    method: str = "quads"
    epoch: float | None = None
    channel: str | int | None = None
    utc_offset_hours: float | None = None
    site: Site | None = None
    detector: StarDetector = StarDetector()

    def solve_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`startrack.solve_image` (without the epoch)."""
        return {"fov_deg": self.fov_deg, "fov_range_deg": self.fov_range_deg, "camera": self.camera,
                "method": self.method}

    def settings(self, epoch: float) -> dict[str, Any]:
        """The JSON-able ``settings`` of a record solved with these options at ``epoch``."""
        default = StarDetector().settings()
        changed = {k: v for k, v in self.detector.settings().items() if v != default[k]}
        fov_range = None if self.fov_range_deg is None else list(self.fov_range_deg)
        return {"fov_deg": self.fov_deg, "fov_range_deg": fov_range,
                "camera": None if self.camera is None else self.camera.name, "method": self.method,
                "channel": self.channel, "epoch_jyear": epoch, "detector": changed}


def solve_options_from(options: Mapping[str, Any] | None) -> SolveOptions:
    """:class:`SolveOptions` from a mapping (module docstring).

    Raises
    ------
    InvalidInputError
        An unknown key (listing the valid ones), a bad FOV, unknown camera preset or site, or a
        detector setting the :class:`~startrack.detect.StarDetector` refuses.
    """
    options = dict(options or {})
    detector_keys = {k: options.pop(k) for k in list(options) if k in _DETECTOR_FIELDS and k != "channel"}
    unknown = sorted(set(options) - set(_OPTION_KEYS))
    if unknown:
        raise InvalidInputError(f"unknown solve option {unknown[0]!r}; valid options: {', '.join(_OPTION_KEYS)} "
                                "or a StarDetector setting")
    camera = options.get("camera")
    camera = get_preset(camera) if isinstance(camera, str) else camera
    if camera is not None and not isinstance(camera, Camera):
        raise InvalidInputError(f"camera must be a preset name or a Camera, got {camera!r}")
    site = options.get("site")
    site = get_site(site) if isinstance(site, str) else site
    epoch = options.get("epoch")
    return SolveOptions(fov_deg=_fov(options.get("fov_deg")), fov_range_deg=_fov_range(options.get("fov_range_deg")),
                        camera=camera, method=str(options.get("method") or "quads"),
                        epoch=None if epoch is None else epoch_jyear(epoch), channel=options.get("channel"),
                        utc_offset_hours=options.get("utc_offset_hours"), site=site,
                        detector=_detector(options.get("detector"), detector_keys))


def _fov(value) -> float | None:
    return None if value is None else check_fov_deg(value, "fov_deg")


def _fov_range(value) -> tuple[float, float] | None:
    if value is None:
        return None
    if isinstance(value, str) or len(value) != 2:
        raise InvalidInputError(f"fov_range_deg must be a pair (low, high) in deg, got {value!r}")
    lo, hi = (check_fov_deg(v, "fov_range_deg") for v in value)
    if lo > hi:
        raise InvalidInputError(f"fov_range_deg must be (low, high) with low <= high, got ({lo:g}, {hi:g})")
    return lo, hi


def _detector(value, extra: Mapping[str, Any]) -> StarDetector:
    if isinstance(value, StarDetector):
        return replace(value, **extra)
    settings = {**dict(value or {}), **extra}
    unknown = sorted(set(settings) - set(_DETECTOR_FIELDS))
    if unknown:
        raise InvalidInputError(f"unknown detector setting {unknown[0]!r}; valid settings: "
                                f"{', '.join(_DETECTOR_FIELDS)}")
    try:
        return StarDetector(**settings)
    except TypeError as exc:
        raise InvalidInputError(f"detector settings: {exc}") from None


def image_paths(paths: str | os.PathLike | Sequence[str | os.PathLike]) -> list[Path]:
    """Image files of ``paths``: files as given, each folder's image files (by suffix, in name
    order with numbers compared as numbers, :func:`startrack.io.in_name_order`; not recursive).
    Raises InvalidInputError for a missing path or a folder with none."""
    items = [paths] if isinstance(paths, str | os.PathLike) else list(paths)
    out: list[Path] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            found = in_name_order([p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES])
            if not found:
                raise InvalidInputError(f"folder {path} holds no image files ({', '.join(sorted(IMAGE_SUFFIXES))})")
            out.extend(found)
        elif path.is_file():
            out.append(path)
        else:
            raise InvalidInputError(f"{path}: no such file or folder")
    if not out:
        raise InvalidInputError("give at least one image file or folder")
    return out


def records_from_images(paths, *, solve_options: Mapping[str, Any] | None = None,
                        progress: Callable[[int, int], None] | None = None, name: str | None = None) -> ResultSet:
    """Read, detect (:class:`~startrack.detect.StarDetector`) and solve
    (:func:`startrack.solve_image`) each image file; one result set.

    Parameters
    ----------
    paths : path or sequence of paths
        Image files or folders of them (:func:`image_paths`).
    solve_options : mapping, optional
        See the module docstring.
    progress : callable, optional
        Called as ``progress(done, total)`` after each image.
    name : str, optional
        The set's name; default the folder's name (of the first file).

    Returns
    -------
    ResultSet
        One record per file in order, named by the file name.
    """
    options = solve_options_from(solve_options)
    files = image_paths(paths)
    records, kept_px = [], 0
    for i, path in enumerate(files):
        record = record_from_file(path, options)
        if record.image is not None:
            kept_px += record.image.size
            if kept_px > KEEP_PIXELS_MAX:
                record = replace(record, image=None)
        records.append(record)
        if progress is not None:
            progress(i + 1, len(files))
    return ResultSet(name or files[0].parent.name or "images", tuple(records))


def record_from_file(path: Path, options: SolveOptions) -> ImageRecord:
    """One file's record (a failed one when it cannot be read or detected)."""
    try:
        image = read_image(path, channel=options.channel)
    except (ImageReadError, InvalidInputError, OSError) as exc:
        return _failed(path, options, exc)
    when = _header_time(image, options.utc_offset_hours)
    epoch = jyear_tdb(when) if when is not None else options.epoch or epoch_jyear(_header_epoch(image))
    try:
        solution = solve_image(image, epoch=epoch, detector=options.detector, **options.solve_kwargs())
    except InvalidInputError as exc:  # this file's content (size against the camera, no finite pixel)
        return _failed(path, options, exc)
    return ImageRecord(name=path.name, solution=solution, image=image.data, time=when,
                       settings=options.settings(epoch), path=path, camera=options.camera, site=options.site,
                       true_rot_cam_from_icrs=true_rotation_from_file(image))


def _failed(path: Path, options: SolveOptions, exc: Exception) -> ImageRecord:
    reason = UNREADABLE + " ".join(str(exc).split())
    return ImageRecord(name=path.name, solution=AttitudeSolution(status=Status.TOO_FEW_STARS, reason=reason),
                       settings=options.settings(options.epoch or epoch_jyear(None)), path=path,
                       camera=options.camera, site=options.site)


def _header_time(image: Image, utc_offset_hours: float | None) -> Time | None:
    """The image's time from its header, None when it has none (or a zone-less EXIF time)."""
    try:
        return time_from_header(image.header, utc_offset_hours=utc_offset_hours)
    except InvalidInputError:
        return None


def _header_epoch(image: Image) -> float | None:
    """CATEPOCH of a simulated FITS file (the catalog epoch it was rendered at)."""
    value = image.header.get("CATEPOCH")
    return float(value) if isinstance(value, int | float) else None


def true_rotation_from_file(image: Image) -> Rotation | None:
    """The true ``rot_cam_from_icrs`` of a file written by ``startrack simulate``: FITS cards
    ``TRUE_QX .. TRUE_QW`` or the ``<stem>.truth.json`` sidecar (``qx .. qw``); else None."""
    cards = [image.header.get(f"TRUE_Q{c}") for c in "XYZW"]
    if all(isinstance(v, int | float) for v in cards):
        return Rotation.from_quat(cards)
    if image.path is None:
        return None
    sidecar = image.path.with_name(image.path.stem + ".truth.json")
    try:
        data = json.loads(sidecar.read_text())
        return Rotation.from_quat([float(data[k]) for k in ("qx", "qy", "qz", "qw")])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def record_pixels(record: ImageRecord) -> np.ndarray:
    """The record's pixels: ``record.image``, else read again from ``record.path`` (with the
    channel of its settings). Raises InvalidInputError naming the record when it has neither."""
    if record.image is not None:
        return np.asarray(record.image)
    if record.path is None:
        raise InvalidInputError(f"record {record.name!r} has no image and no path: this analysis needs the pixels")
    return read_image(record.path, channel=record.settings.get("channel")).data


def solve_kwargs_of(record: ImageRecord) -> dict[str, Any]:
    """The :func:`startrack.solve_image` options to solve ``record``'s image again as it was.

    The camera comes from ``record.camera``, else the FOV options of its settings; when they
    name none, a solved record's own FOV is used, else the default range is searched.
    """
    settings = record.settings
    kwargs: dict[str, Any] = {"method": settings.get("method") or "quads", "epoch": settings.get("epoch_jyear")}
    if record.camera is not None:
        return {**kwargs, "camera": record.camera}
    if settings.get("fov_deg") is not None:
        return {**kwargs, "fov_deg": float(settings["fov_deg"])}
    if settings.get("fov_range_deg") is not None:
        return {**kwargs, "fov_range_deg": tuple(float(v) for v in settings["fov_range_deg"])}
    if record.solution.solved:
        return {**kwargs, "fov_deg": float(record.solution.fov_deg)}
    return kwargs


def detector_of(record: ImageRecord) -> StarDetector:
    """The detector ``record`` was processed with (its settings' ``detector``, else the default)."""
    changed = dict(record.settings.get("detector") or {})
    changed.pop("dark_frame", None)
    for key in ("dark_columns", "smear_px"):
        if isinstance(changed.get(key), list):
            changed[key] = tuple(changed[key])
    return _detector(changed, {})
