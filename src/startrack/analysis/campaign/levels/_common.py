"""Parameters the levels share: the camera's field and size, and how the solver is called."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ....identify import MATCHERS, MAX_FOV_DEG, MIN_FOV_DEG
from .._params import Param, SpecError

CAMERA_PARAMS = (
    Param("fov_deg", "float", 15.0, "horizontal field of view of the pinhole camera, edge to edge (deg)",
          lo=MIN_FOV_DEG, hi=MAX_FOV_DEG),
    Param("width", "int", 1024, "image width (px)", lo=16, hi=20000),
    Param("height", "int", 1024, "image height (px)", lo=16, hi=20000),
)

SOLVER_PARAMS = (
    Param("fov_known", "bool", True, "true: solve with fov_deg given (trusted to 3 %); false: search fov_range_deg"),
    Param("fov_range_deg", "floats", (5.0, 35.0), "FOV range searched when fov_known is false (deg)",
          lo=MIN_FOV_DEG, hi=MAX_FOV_DEG, length=2),
    Param("method", "str", "quads", "the lost-in-space matcher (docs/identification.md)",
          choices=tuple(name for name in MATCHERS if name != "overlay")),
    Param("epoch_jyear", "float", 2025.0, "epoch of the star positions, scene and solver (Julian year, TDB)",
          lo=1900.0, hi=2100.0),
)


def check_solver(params: Mapping[str, Any]) -> None:
    """Refuse an empty FOV range."""
    lo, hi = params["fov_range_deg"]
    if lo > hi:
        raise SpecError(f"fov_range_deg: the lower end must not exceed the upper, got [{lo:g}, {hi:g}]")


def solver_kwargs(params: Mapping[str, Any]) -> dict[str, Any]:
    """Keyword arguments of ``solve_stars`` / ``solve_image`` for these parameters (FOV
    knowledge, matcher, epoch)."""
    fov = {"fov_deg": params["fov_deg"]} if params["fov_known"] else {"fov_range_deg": tuple(params["fov_range_deg"])}
    return {**fov, "method": params["method"], "epoch": params["epoch_jyear"]}
