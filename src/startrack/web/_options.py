"""The ``options`` of a solve job: checked once, when the job is submitted (422 naming the field).

``options`` is a JSON object; every key is optional:

=======================  ======================================================================
``fov_deg``              horizontal field of view, deg (0.5 to 150), trusted to 3 %
``fov_range_deg``        ``[low, high]`` to search, deg (0.5 to 150; default the solver's, 3 to 100)
``camera``               a camera preset (:data:`startrack.camera.PRESETS`) or a saved profile
``epoch``                catalog epoch, Julian year (default: from ``time``, else J2000.0)
``time``                 UTC time of the exposure, ISO 8601 (default: from the file's header)
``utc_offset_hours``     offset of a zone-less EXIF clock from UTC, -14 to 14
``site``                 a saved or built-in site (:mod:`startrack.calibrate._sites`), or
``latitude_deg``, ``longitude_deg`` [, ``height_m``]: a ground photo (altitude and azimuth)
``lens_correction``      true (default): use the camera's distortion; false: its pinhole
``atmosphere_correction`` true (default): a ground photo is refitted to the apparent, refracted sky
``method``               the lost-in-space matcher (default "quads")
``channel``              "r", "g" or "b" (default R + G + B)
``detection_preset``     a preset of :mod:`._presets` (default "default")
``detection``            settings of :class:`startrack.detect.StarDetector` (override the preset)
``fit_camera``           fit focal length and distortion on a trial solve, then solve again
                         (default: true for the "auto" preset, else false)
``time_limit_s``         a shorter time limit for this job, s (the server's ``--time-limit-s``
                         is the longest)
``guided``               once solved, also measure the catalog stars the solution predicts where
                         nothing was detected and refit on them (default false;
                         :mod:`startrack.identify._guided`)
=======================  ======================================================================

:func:`validate_options` returns the normalised options (plain JSON, kept in ``job.json`` and in
``rerun.json``): the camera is expanded to its fields so the job can be repeated anywhere.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path
from typing import Any

from astropy.time import Time

from ..calibrate import Site, get_site
from ..camera import PRESETS as CAMERA_PRESETS
from ..camera import Camera, get_preset, preset_key
from ..detect import StarDetector
from ..errors import InvalidInputError
from ..identify import MATCHERS
from ..solve import check_fov_deg, epoch_jyear
from . import _json_text as json_text
from ._presets import PRESETS

PROFILE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
DETECTOR_KEYS = tuple(f.name for f in dataclasses.fields(StarDetector) if f.name not in ("dark_frame", "channel"))
METHODS = tuple(name for name in MATCHERS if name != "overlay")
KEYS = ("fov_deg", "fov_range_deg", "camera", "epoch", "time", "utc_offset_hours", "site", "latitude_deg",
        "longitude_deg", "height_m", "lens_correction", "atmosphere_correction", "method", "channel",
        "detection_preset", "detection", "fit_camera", "time_limit_s", "guided")
MAX_OPTIONS_BYTES = 16_384


class OptionError(InvalidInputError):
    """An invalid option; ``field`` names it (``options.fov_deg``, ``options.detection.sigma``)."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field = field


def parse_options(text: str | None, cameras_dir: Path) -> dict[str, Any]:
    """The ``options`` form field (JSON text, may be empty) checked by :func:`validate_options`."""
    if text is None or not text.strip():
        return validate_options({}, cameras_dir)
    if len(text.encode()) > MAX_OPTIONS_BYTES:
        raise OptionError("options", f"must be at most {MAX_OPTIONS_BYTES} bytes of JSON")
    try:
        value = json_text.loads(text)
    except ValueError as exc:
        raise OptionError("options", f"is not valid JSON ({exc})") from None
    return validate_options(value, cameras_dir)


def validate_options(options: Any, cameras_dir: Path) -> dict[str, Any]:
    """Checked, normalised options (module docstring); OptionError naming the first bad field."""
    if not isinstance(options, dict):
        raise OptionError("options", f"must be a JSON object, got {type(options).__name__}")
    unknown = sorted(set(options) - set(KEYS))
    if unknown:
        raise OptionError(f"options.{unknown[0]}", f"unknown option; valid options: {', '.join(KEYS)}")
    out: dict[str, Any] = {"fov_deg": None, "fov_range_deg": None, "camera": None}
    _fov(options, out, cameras_dir)
    _time(options, out)
    _site(options, out)
    out["lens_correction"] = _bool(options, "lens_correction", True)
    out["atmosphere_correction"] = _bool(options, "atmosphere_correction", True)
    out["method"] = _choice(options, "method", METHODS, "quads")
    out["channel"] = _choice(options, "channel", ("r", "g", "b"), None)
    out["detection_preset"] = _choice(options, "detection_preset", tuple(PRESETS), "default")
    out["detection"] = _detection(options.get("detection"), out["detection_preset"])
    out["fit_camera"] = _bool(options, "fit_camera", out["detection_preset"] == "auto")
    out["time_limit_s"] = _number(options, "time_limit_s", 0.1, 86400.0)
    out["guided"] = _bool(options, "guided", False)
    if out["method"] != "quads" and out["fov_deg"] is None and out["camera"] is None:
        raise OptionError("options.method", f"{out['method']!r} needs fov_deg or camera; only 'quads' searches "
                                            "a range of fields of view")
    return out


def _number(options: dict, key: str, low: float, high: float) -> float | None:
    value = options.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise OptionError(f"options.{key}", f"must be a finite number, got {value!r}")
    if not low <= value <= high:
        raise OptionError(f"options.{key}", f"must be within {low:g}..{high:g}, got {value:g}")
    return float(value)


def _bool(options: dict, key: str, default: bool) -> bool:
    value = options.get(key, default)
    if not isinstance(value, bool):
        raise OptionError(f"options.{key}", f"must be true or false, got {value!r}")
    return value


def _choice(options: dict, key: str, choices: tuple[str, ...], default: str | None) -> str | None:
    value = options.get(key, default)
    if value is not None and value not in choices:
        raise OptionError(f"options.{key}", f"must be one of {', '.join(choices)}, got {value!r}")
    return value


def _fov(options: dict, out: dict, cameras_dir: Path) -> None:
    given = [k for k in ("fov_deg", "fov_range_deg", "camera") if options.get(k) is not None]
    if len(given) > 1:
        raise OptionError(f"options.{given[1]}", f"give one of fov_deg, fov_range_deg and camera, not {given[0]} too")
    if options.get("fov_deg") is not None:
        out["fov_deg"] = _checked_fov(options["fov_deg"], "options.fov_deg")
    value = options.get("fov_range_deg")
    if value is not None:
        if not isinstance(value, list) or len(value) != 2:
            raise OptionError("options.fov_range_deg", f"must be [low, high] in deg, got {value!r}")
        lo, hi = (_checked_fov(v, "options.fov_range_deg") for v in value)
        if lo > hi:
            raise OptionError("options.fov_range_deg", f"needs low <= high, got [{lo:g}, {hi:g}]")
        out["fov_range_deg"] = [lo, hi]
    if options.get("camera") is not None:
        out["camera"] = camera_to_json(load_camera(options["camera"], cameras_dir))


def _checked_fov(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise OptionError(field, f"must be a number of degrees, got {value!r}")
    try:
        return check_fov_deg(value, "it")
    except InvalidInputError as exc:
        raise OptionError(field, str(exc).removeprefix("it ")) from None


def _time(options: dict, out: dict) -> None:
    epoch = _number(options, "epoch", 1000.0, 3000.0)
    out["epoch"] = None if epoch is None else epoch_jyear(epoch)
    out["utc_offset_hours"] = _number(options, "utc_offset_hours", -14.0, 14.0)
    value = options.get("time")
    out["time"] = None
    if value is not None:
        message = f"must be an ISO 8601 UTC time such as 2024-08-12T03:15:00, got {value!r}"
        if not isinstance(value, str):
            raise OptionError("options.time", message)
        try:
            out["time"] = Time(value, scale="utc").isot
        except ValueError:
            raise OptionError("options.time", message) from None


def _site(options: dict, out: dict) -> None:
    lat = _number(options, "latitude_deg", -90.0, 90.0)
    lon = _number(options, "longitude_deg", -180.0, 360.0)
    height = _number(options, "height_m", -500.0, 9000.0)
    name = options.get("site")
    out["site"] = None
    if name is not None:
        if lat is not None or lon is not None:
            raise OptionError("options.site", "give site or latitude_deg / longitude_deg, not both")
        if not isinstance(name, str):
            raise OptionError("options.site", f"must be a site name, got {name!r}")
        try:
            out["site"] = dataclasses.asdict(get_site(name))
        except InvalidInputError as exc:
            raise OptionError("options.site", str(exc)) from None
    elif (lat is None) != (lon is None):
        raise OptionError("options.longitude_deg" if lon is None else "options.latitude_deg",
                          "give both latitude_deg and longitude_deg (or site)")
    elif lat is not None and lon is not None:
        out["site"] = dataclasses.asdict(Site("custom", lat, lon, height or 0.0))


def _detection(value: Any, preset: str) -> dict[str, Any]:
    """Checked detector settings (the job's own; the preset is applied when the job runs)."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise OptionError("options.detection", f"must be an object of detector settings, got {value!r}")
    unknown = sorted(set(value) - set(DETECTOR_KEYS))
    if unknown:
        raise OptionError(f"options.detection.{unknown[0]}",
                          f"unknown detector setting; valid settings: {', '.join(DETECTOR_KEYS)}")
    settings = {k: tuple(v) if isinstance(v, list) else v for k, v in value.items()}
    base = {} if preset == "auto" else dict(PRESETS[preset].settings)
    try:
        StarDetector(**{**base, **settings})
    except (InvalidInputError, TypeError, ValueError) as exc:
        key = next((k for k in settings if k in str(exc)), None)
        raise OptionError("options.detection" + (f".{key}" if key else ""), " ".join(str(exc).split())) from None
    return {k: list(v) if isinstance(v, tuple) else v for k, v in settings.items()}


# --- cameras ----------------------------------------------------------------------------------
def camera_to_json(camera: Camera) -> dict[str, Any]:
    """A camera's fields as plain JSON values (a profile)."""
    return {k: (float(v) if isinstance(v, float) else v) for k, v in dataclasses.asdict(camera).items()}


def camera_from_json(data: dict[str, Any], field: str = "camera") -> Camera:
    """A :class:`~startrack.camera.Camera` from its fields; OptionError naming ``field`` otherwise."""
    names = {f.name for f in dataclasses.fields(Camera)}
    if not isinstance(data, dict) or set(data) - names:
        bad = sorted(set(data) - names) if isinstance(data, dict) else data
        raise OptionError(field, f"a camera profile holds the fields {', '.join(sorted(names))}; got {bad!r}")
    try:
        return Camera(**data)
    except (InvalidInputError, TypeError) as exc:
        raise OptionError(field, " ".join(str(exc).split())) from None


def load_camera(name: Any, cameras_dir: Path) -> Camera:
    """A camera preset, else the saved profile ``<cameras_dir>/<name>.json``."""
    if not isinstance(name, str) or not PROFILE_NAME.match(name):
        raise OptionError("options.camera", f"must be a camera preset or profile name, got {name!r}")
    if preset_key(name) in CAMERA_PRESETS:
        return get_preset(name)
    path = cameras_dir / f"{name}.json"
    if not path.is_file():
        known = ", ".join(sorted(CAMERA_PRESETS) + profile_names(cameras_dir))
        raise OptionError("options.camera", f"unknown camera {name!r}; known cameras: {known}")
    return camera_from_json(json.loads(path.read_text()), "options.camera")


def profile_names(cameras_dir: Path) -> list[str]:
    """Names of the saved camera profiles."""
    if not cameras_dir.is_dir():
        return []
    return sorted(p.stem for p in cameras_dir.glob("*.json") if PROFILE_NAME.match(p.stem))
