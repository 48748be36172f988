"""Simulate from the page: a star image with its truth, rendered by the worker as the job's input.

The parameters (a JSON object, every key optional) are those of ``startrack simulate``'s scene:
``fov_deg`` (default 15), ``width`` / ``height`` (default 1024), ``ra_deg`` / ``dec_deg`` /
``roll_deg`` (default: a random attitude from ``seed``), ``max_mag`` (default 7.5), ``sensor``
(a preset, default "generic-cmos"), ``epoch`` (Julian year, default 2000.0) and ``seed``
(default: a fresh one, recorded). The frame is written with :func:`startrack.io._truth_files.write_frame`
as ``input.fits`` (the truth in its header and ``TRUTH`` table), exactly what
``startrack simulate --out x.fits`` writes, so the job then runs as an upload of that file would.
"""

from __future__ import annotations

import math
import secrets
from pathlib import Path
from typing import Any

import numpy as np

from ..camera import Camera
from ..errors import InvalidInputError
from ..frames import random_rotations, rotation_from_radec_roll
from ._options import OptionError

DEFAULTS: dict[str, Any] = {"fov_deg": 15.0, "width": 1024, "height": 1024, "ra_deg": None, "dec_deg": None,
                            "roll_deg": 0.0, "max_mag": 7.5, "sensor": "generic-cmos", "epoch": 2000.0, "seed": None}
LIMITS = {"fov_deg": (1.0, 60.0), "width": (64, 4096), "height": (64, 4096), "ra_deg": (0.0, 360.0),
          "dec_deg": (-90.0, 90.0), "roll_deg": (-360.0, 360.0), "max_mag": (3.0, 9.0), "epoch": (1900.0, 2100.0),
          "seed": (0, 2**31 - 1)}
INTEGER = ("width", "height", "seed")


def validate_simulation(params: Any) -> dict[str, Any]:
    """Checked parameters with their defaults (a fresh seed when none); OptionError naming the field."""
    from ..simulate import SENSOR_PRESETS

    if not isinstance(params, dict):
        raise OptionError("simulate", f"must be a JSON object of scene parameters, got {type(params).__name__}")
    unknown = sorted(set(params) - set(DEFAULTS))
    if unknown:
        raise OptionError(f"simulate.{unknown[0]}", f"unknown parameter; valid: {', '.join(DEFAULTS)}")
    out = {**DEFAULTS, **{k: v for k, v in params.items() if v is not None}}
    for key, (low, high) in LIMITS.items():
        value = out[key]
        if value is None:
            continue
        kind_ok = isinstance(value, int) if key in INTEGER else isinstance(value, int | float)
        if isinstance(value, bool) or not kind_ok or not math.isfinite(value) or not low <= value <= high:
            what = "a whole number" if key in INTEGER else "a number"
            raise OptionError(f"simulate.{key}", f"must be {what} within {low:g}..{high:g}, got {value!r}")
    if (out["ra_deg"] is None) != (out["dec_deg"] is None):
        raise OptionError("simulate.dec_deg" if out["dec_deg"] is None else "simulate.ra_deg",
                          "give both ra_deg and dec_deg, or neither (a random attitude)")
    if not isinstance(out["sensor"], str) or out["sensor"] not in SENSOR_PRESETS:
        raise OptionError("simulate.sensor", f"must be one of {', '.join(sorted(SENSOR_PRESETS))}, "
                                             f"got {out['sensor']!r}")
    if out["seed"] is None:
        out["seed"] = secrets.randbelow(2**31)
    return out


def render(params: dict[str, Any], path: Path) -> None:
    """Render the checked scene and write it (image + truth) to ``path`` (a .fits file)."""
    from ..io import write_frame
    from ..simulate import get_sensor_preset, simulate_frame

    rng = np.random.default_rng(params["seed"])
    try:
        camera = Camera.from_fov(params["width"], params["height"], params["fov_deg"], name="simulated")
    except InvalidInputError as exc:
        raise OptionError("simulate", str(exc)) from None
    if params["ra_deg"] is None:
        rot = random_rotations(None, rng)
    else:
        rot = rotation_from_radec_roll(*(math.radians(params[k]) for k in ("ra_deg", "dec_deg", "roll_deg")))
    sim = simulate_frame(camera, rot, max_mag=params["max_mag"], sensor=get_sensor_preset(params["sensor"]),
                         rng=rng, epoch_jyear=params["epoch"])
    write_frame(path, sim.image, sim.truth)
