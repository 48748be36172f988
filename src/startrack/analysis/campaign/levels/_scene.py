"""Scenario parameters of a rendered frame, and the simulator and detector objects they make.

Besides the few named here (camera and sensor presets, exposure, magnitude limit, rate, rolling
shutter, the true lens's distortion, sky background, the stellar aberration the rendered stars
show), every field of the simulator's ``Optics``
and ``Detector`` is a parameter under its own name (default "auto": the sensor preset's value),
every switch of ``NoiseModel`` is ``noise_<field>``, and every setting of ``StarDetector`` is
``detect_<field>`` (default: the detector's own), generated from the dataclasses so that a new
setting is a campaign parameter at once. The objects check their own values; :func:`check_scene`
builds them for every cell before any work, so a bad value is refused naming its key.
"""

from __future__ import annotations

import dataclasses
import functools
import sys
from collections.abc import Mapping
from typing import Any, Literal, get_args, get_origin

import numpy as np
from astropy.time import Time

from ....calibrate import aberrate, earth_state
from ....camera import PRESETS, Camera, get_preset
from ....detect import StarDetector
from ....errors import InvalidInputError
from ....simulate import (
    SENSOR_PRESETS,
    Detector,
    NoiseModel,
    Optics,
    Sensor,
    SkyBackground,
    SkyModel,
    get_sensor_preset,
)
from .._params import Param, SpecError

_SCALARS = {"float": "float", "int": "int", "bool": "bool", "str": "str"}


def _kind(cls: type, name: str, annotation: str) -> tuple[str, bool, tuple[str, ...] | None] | None:
    """(kind, optional, choices) of the field ``name`` of ``cls`` by its annotation, or None when it
    is not a scalar; a ``Literal`` alias (``ThresholdMethod``) of the module of the class that
    declares the field (``cls`` or a base) is a str with its choices."""
    parts = [p.strip() for p in annotation.split("|")]
    optional = "None" in parts
    parts = [p for p in parts if p != "None"]
    if len(parts) != 1:
        return None
    owner = next(c for c in cls.__mro__ if name in vars(c).get("__annotations__", {}))
    alias = vars(sys.modules[owner.__module__]).get(parts[0])
    if get_origin(alias) is Literal:
        return "str", optional, get_args(alias)
    return (_SCALARS[parts[0]], optional, None) if parts[0] in _SCALARS else None


def dataclass_params(cls: type, prefix: str, doc: str, *, auto: bool, skip: tuple[str, ...] = ()) -> tuple[Param, ...]:
    """One :class:`Param` per scalar field of ``cls``, named ``prefix + field``.

    With ``auto`` the default is "auto" (None: keep the value of the object the scenario starts
    from, e.g. the sensor preset's); otherwise the field's own default.
    """
    out = []
    for f in dataclasses.fields(cls):
        kind = _kind(cls, f.name, str(f.type))
        if kind is None or f.name in skip or (f.default is dataclasses.MISSING and not auto):
            continue
        default = None if auto else f.default
        out.append(Param(prefix + f.name, kind[0], default, f"{doc}.{f.name}", optional=auto or kind[1],
                         choices=kind[2]))
    return tuple(out)


FRAME_PARAMS = (
    Param("camera", "str", "", 'a camera preset ("" : a pinhole camera from fov_deg, width, height)',
          choices=("", *sorted(PRESETS))),
    Param("sensor", "str", "generic-cmos", "the sensor preset (startrack.simulate.SENSOR_PRESETS)",
          choices=tuple(sorted(SENSOR_PRESETS))),
    Param("exposure_s", "float", None, "exposure time (s); auto: the sensor's", lo=1e-6, hi=3600.0, optional=True),
    Param("max_mag", "float", 7.5, "faintest catalog star rendered (V)", lo=-2.0, hi=16.0),
    Param("rate_deg_s", "floats", (0.0, 0.0, 0.0), "camera angular rate, camera frame (deg/s)",
          lo=-360.0, hi=360.0, length=3),
    Param("line_time_s", "float", 0.0, "rolling shutter: delay between rows (s); 0 is a global shutter",
          lo=0.0, hi=1.0),
    Param("k1", "float", None, "radial distortion k1 of the true lens; auto: the camera's", lo=-5.0, hi=5.0,
          optional=True),
    Param("k2", "float", None, "radial distortion k2 of the true lens; auto: the camera's", lo=-5.0, hi=5.0,
          optional=True),
    Param("calibrated", "bool", False, "the solver is given the true camera (focal length and distortion)"),
    Param("sky_mag_arcsec2", "float", None, "sky background (V mag per arcsec^2); auto: none", lo=0.0, hi=40.0,
          optional=True),
)

APPARENT_PARAMS = (
    Param("aberration_annual", "bool", False,
          "render the stars where the annual aberration of the Earth's barycentric velocity at epoch_jyear "
          "puts them (erfa.epv00; up to 20.5 arcsec); the solver's catalog has mean places"),
    Param("aberration_velocity_km_s", "floats", (0.0, 0.0, 0.0),
          "observer velocity about the geocentre (GCRS axes, km/s) whose aberration the rendered stars show "
          "(a 7.5 km/s low orbit: up to 5.2 arcsec)", lo=-1000.0, hi=1000.0, length=3),
)
"""Apparent-place effects of the rendered sky (the image level's; a frame without them shows the
catalog's mean places at ``epoch_jyear``)."""

SENSOR_FIELD_PARAMS = (dataclass_params(Optics, "", "Optics", auto=True)
                       + dataclass_params(Detector, "", "Detector", auto=True))
NOISE_PARAMS = dataclass_params(NoiseModel, "noise_", "NoiseModel", auto=False)
DETECT_PARAMS = dataclass_params(StarDetector, "detect_", "StarDetector", auto=False)


def frame_camera(params: Mapping[str, Any]) -> Camera:
    """The true camera: the preset, or a pinhole from the FOV and size; with the lens's k1, k2."""
    camera = (get_preset(params["camera"]) if params["camera"]
              else Camera.from_fov(params["width"], params["height"], params["fov_deg"], name="pinhole"))
    lens = {k: params[k] for k in ("k1", "k2") if params[k] is not None}
    return camera.with_distortion(**lens) if lens else camera


def _overrides(cls: type, params: Mapping[str, Any]) -> dict[str, Any]:
    names = {f.name for f in dataclasses.fields(cls)}
    return {k: v for k, v in params.items() if k in names and v is not None and not k.startswith(("noise_", "detect_"))}


@functools.lru_cache(maxsize=64)
def _sensor(name: str, exposure_s: float | None, optics: tuple, detector: tuple) -> Sensor:
    sensor = get_sensor_preset(name)
    sensor = dataclasses.replace(sensor, optics=dataclasses.replace(sensor.optics, **dict(optics)),
                                 detector=dataclasses.replace(sensor.detector, **dict(detector)))
    return sensor if exposure_s is None else sensor.with_exposure(exposure_s)


def frame_sensor(params: Mapping[str, Any]) -> Sensor:
    """The sensor preset with the exposure and every Optics / Detector field the scenario sets."""
    return _sensor(params["sensor"], params["exposure_s"], tuple(sorted(_overrides(Optics, params).items())),
                   tuple(sorted(_overrides(Detector, params).items())))


def frame_noise(params: Mapping[str, Any]) -> NoiseModel:
    """The noise switches ``noise_<field>``."""
    return NoiseModel(**{f.name: params["noise_" + f.name] for f in dataclasses.fields(NoiseModel)})


def frame_detector(params: Mapping[str, Any]) -> StarDetector:
    """The star detector of the ``detect_<field>`` settings."""
    names = {f.name for f in dataclasses.fields(StarDetector)}
    return StarDetector(**{k[7:]: v for k, v in params.items() if k.startswith("detect_") and k[7:] in names})


def frame_rate_rad_s(params: Mapping[str, Any]) -> np.ndarray | None:
    """The camera rate (rad/s, camera frame), or None when it is zero."""
    rate = np.radians(np.asarray(params["rate_deg_s"], dtype=float))
    return rate if np.any(rate) else None


def frame_sky(params: Mapping[str, Any]) -> SkyBackground | None:
    mu = params["sky_mag_arcsec2"]
    return None if mu is None else SkyBackground(mag_arcsec2=mu)


def observer_velocity_m_s(params: Mapping[str, Any]) -> np.ndarray | None:
    """The observer's barycentric velocity (m/s, ICRS axes) whose aberration the frame shows, or
    None without aberration: the Earth's at ``epoch_jyear`` when ``aberration_annual``, plus
    ``aberration_velocity_km_s``."""
    velocity = np.asarray(params.get("aberration_velocity_km_s", (0.0, 0.0, 0.0)), dtype=float) * 1e3
    if params.get("aberration_annual", False):
        velocity = velocity + earth_state(Time(params["epoch_jyear"], format="jyear", scale="tdb")).velocity_m_s
    return velocity if np.any(velocity) else None


@functools.lru_cache(maxsize=8)
def _aberrated_sky(max_mag: float, epoch_jyear: float, velocity_m_s: tuple[float, float, float]) -> SkyModel:
    sky = SkyModel.from_catalog(max_mag=max_mag, epoch_jyear=epoch_jyear)
    return SkyModel(vectors_icrs=aberrate(sky.vectors_icrs, velocity_m_s), mags=sky.mags, ids=sky.ids,
                    epoch_jyear=sky.epoch_jyear, b_v=sky.b_v)


def frame_sky_model(params: Mapping[str, Any]) -> SkyModel | None:
    """The stars to render: None (the simulator's own Hipparcos sky at ``epoch_jyear``) without
    aberration, else that sky with every star moved by :func:`startrack.calibrate._apparent.aberrate`
    (exact Lorentz form) for :func:`observer_velocity_m_s`; kept per (magnitude limit, epoch,
    velocity), so a cell builds it once per process."""
    velocity = observer_velocity_m_s(params)
    if velocity is None:
        return None
    return _aberrated_sky(float(params["max_mag"]), float(params["epoch_jyear"]), tuple(float(v) for v in velocity))


def check_scene(params: Mapping[str, Any]) -> None:
    """Build every object of a cell once, so that a value they refuse is reported before any work."""
    for build in (frame_camera, frame_sensor, frame_noise, frame_detector):
        try:
            build(params)
        except (InvalidInputError, ValueError, TypeError) as exc:
            raise SpecError(f"{build.__name__.replace('frame_', '')} settings: {exc}") from None
