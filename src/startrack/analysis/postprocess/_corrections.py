"""Analysis 5: attitude error with and without the lens correction and with and without the
atmosphere correction (Fowler 2013 Ch. 9 §VIII.B and §IX; result sets 4 against 5 and
1 against 2 of Table 9.3).

For each solved record the attitude is fitted again (Davenport's q-method,
:func:`startrack.attitude.q_method`) to the *same* matched stars four ways:

- **lens** on: the spots turned into directions through the calibrated lens model (distortion
  included); off: through the pinhole with the same focal lengths and principal point (Fowler 2013
  §1.4, "Correct for Lens" switched off). The lens model is the ``camera`` parameter's preset,
  else the camera the record was solved with, else the simulator's camera, else the solution's;
- **atmosphere** on: the catalog directions made what a camera on the ground sees, as
  :func:`startrack.calibrate._ground_solve.solve_ground_photo` does (apparent place,
  :func:`~startrack.calibrate._apparent.apparent_vectors`, then Bennett refraction at the site,
  :func:`~startrack.calibrate._ground.refract_icrs`); off: the catalog directions the solve used.
  It needs the record's time and a site, and is left out otherwise.

Each variant's error is taken against the truth for a simulated record, otherwise against the most
corrected variant (lens and atmosphere on, or lens on when there is no atmosphere correction),
as total, pointing and roll (:func:`.ground.error_arcsec`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ...attitude import q_method
from ...calibrate import apparent_vectors, refract_icrs
from ...camera import Camera, get_preset
from ...catalog import load_catalog
from ...errors import InvalidInputError, require
from ...frames import angle_between
from ...units import ARCSEC
from .._records import ImageRecord
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import new_figure, no_data
from ._ground import SITE_LIMITS, SITE_PARAMS, error_arcsec, site_from_params, true_rotation


def check(params: dict) -> None:
    """The ``camera`` parameter names a preset (:func:`startrack.camera.get_preset` says which)."""
    if params["camera"]:
        try:
            get_preset(params["camera"])
        except InvalidInputError as exc:
            raise InvalidInputError(f"corrections: parameter 'camera': {exc}") from None


INFO = AnalysisInfo(
    name="corrections",
    title="Attitude error with and without lens and atmosphere corrections",
    description="The attitude of each solved image fitted again to the same matched stars with the lens "
                "model on or off (pinhole) and with the atmosphere correction (apparent place and "
                "refraction at the site and time) on or off; errors against the truth for simulated "
                "images, otherwise against the fully corrected attitude. Fowler 2013 Ch. 9 §VIII.B, §IX.",
    min_sets=1, max_sets=6,
    params={"camera": (str, None, "camera preset of the lens model (default: the records' camera)"), **SITE_PARAMS},
    limits=SITE_LIMITS,
    check=check,
)
VARIANTS = ((True, True), (True, False), (False, True), (False, False))
"""(lens, atmosphere), the most corrected first."""
COLUMNS = ("set", "record", "lens", "atmosphere", "against", "total_arcsec", "pointing_arcsec", "roll_arcsec",
           "residual_rms_arcsec", "n_stars")


def pinhole(camera: Camera) -> Camera:
    """The camera without its distortion (same focal lengths, principal point and parity)."""
    return Camera(width=camera.width, height=camera.height, fx=camera.fx, fy=camera.fy, cx=camera.cx,
                  cy=camera.cy, name=f"{camera.name or 'camera'} (pinhole)", source=camera.source,
                  pixel_pitch_um=camera.pixel_pitch_um, mirrored=camera.mirrored)


def lens_model(record: ImageRecord, override: Camera | None) -> Camera:
    """The lens model of ``record`` (module docstring), checked against its image size."""
    det = require(record.solution.detections, "the record's detections")
    truth_camera = None if record.truth is None else record.truth.camera
    camera = next(c for c in (override, record.camera, truth_camera, record.solution.camera) if c is not None)
    if (camera.width, camera.height) != (det.width, det.height):
        raise InvalidInputError(f"corrections: the lens model {camera.name!r} is {camera.width} x {camera.height} "
                                f"px but image {record.name!r} is {det.width} x {det.height} px; give parameter "
                                "'camera' for a preset of that size")
    return camera


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    override = get_preset(params["camera"]) if params["camera"] else None
    site = site_from_params(INFO.name, params, [r for s in sets for r in s.records])
    table: dict[str, list] = {k: [] for k in COLUMNS}
    models: dict[str, bool] = {}
    for s in sets:
        for record in s.records:
            if record.solution.solved and record.solution.detections is not None:
                camera = lens_model(record, override)
                models[camera.name or "camera"] = camera.has_distortion
                _add_rows(table, s.name, record, camera, site)
    fig = _draw(table)
    summary = _summary(table, site)
    summary["lens model"] = ", ".join(f"{name}{'' if distorted else ' (no distortion: lens on = off)'}"
                                      for name, distorted in models.items()) or "none"
    return AnalysisResult(INFO.name, INFO.title, fig, {"errors": table}, summary)


def _add_rows(table: dict[str, list], set_name: str, record: ImageRecord, camera: Camera, site) -> None:
    fits = _variants(record, camera, site)
    truth = true_rotation(record)
    reference = truth if truth is not None else fits[next(v for v in VARIANTS if v in fits)][0]
    against = "truth" if truth is not None else _label(*next(v for v in VARIANTS if v in fits))
    for (lens, atmosphere), (rotation, rms, n) in fits.items():
        total, pointing, roll = error_arcsec(rotation, reference)
        for key, value in zip(COLUMNS, (set_name, record.name, lens, atmosphere, against, total, pointing, roll,
                                        rms, n), strict=True):
            table[key].append(value)


def _label(lens: bool, atmosphere: bool) -> str:
    return "lens and atmosphere corrected" if atmosphere else "lens corrected"


def _variants(record: ImageRecord, camera: Camera, site) -> dict[tuple[bool, bool], tuple[Rotation, float, int]]:
    """The refitted attitude, rms residual (arcsec) and star count of each variant available."""
    sol = record.solution
    idx = sol.matches.det_index
    det = require(sol.detections, "the solution's detections")
    x, y = det.x[idx], det.y[idx]
    observed = {True: camera.pixel_to_vector(x, y), False: pinhole(camera).pixel_to_vector(x, y)}
    references = {False: sol.matches.cat_vectors}
    if site is not None and record.time is not None:
        catalog = load_catalog()
        stars = catalog.take(np.searchsorted(catalog.hip, sol.matches.hip))
        references[True] = refract_icrs(apparent_vectors(stars, record.time), record.time, site)
    out = {}
    for lens, atmosphere in VARIANTS:
        if atmosphere in references:
            out[(lens, atmosphere)] = _fit(observed[lens], references[atmosphere])
    return out


def _fit(observed: NDArray, reference: NDArray) -> tuple[Rotation, float, int]:
    rotation = require(q_method(observed, reference).rotation, "the q-method attitude")
    residual = angle_between(rotation.apply(reference), observed) / ARCSEC
    return rotation, float(np.sqrt(np.mean(residual**2))), int(len(observed))


def _draw(table: dict[str, list]):
    fig, axes = new_figure(1, 3, width_in=3.8, height_in=3.6, title=INFO.title)
    lens, atm = np.asarray(table["lens"], bool), np.asarray(table["atmosphere"], bool)
    for ax, key in zip(axes[0], ("total_arcsec", "pointing_arcsec", "roll_arcsec"), strict=True):
        values = np.abs(np.asarray(table[key], float))
        groups = [(f"lens {'on' if v[0] else 'off'}\natm. {'on' if v[1] else 'off'}", (lens == v[0]) & (atm == v[1]))
                  for v in VARIANTS]
        groups = [(name, values[mask]) for name, mask in groups if mask.any()]
        if not groups:
            no_data(ax, "no solved images")
            continue
        ax.boxplot([g[1] for g in groups], tick_labels=[g[0] for g in groups])
        ax.set_ylabel(key.replace("_arcsec", " error, arcsec").replace("roll", "|roll|"))
        ax.tick_params(axis="x", labelsize=7)
    return fig


def _summary(table: dict[str, list], site) -> dict[str, float | int | str]:
    lens, atm = np.asarray(table["lens"], bool), np.asarray(table["atmosphere"], bool)
    total = np.asarray(table["total_arcsec"], float)
    out: dict[str, float | int | str] = {
        "images": len(set(zip(table["set"], table["record"], strict=True))),
        "site": "none (atmosphere variants left out)" if site is None else site.name,
        "against": ", ".join(sorted(set(table["against"]))) or "none"}
    for v in VARIANTS:
        mask = (lens == v[0]) & (atm == v[1])
        if mask.any():
            out[f"mean total error, lens {'on' if v[0] else 'off'}, atmosphere {'on' if v[1] else 'off'}, arcsec"] = \
                float(np.mean(total[mask]))
    return out
