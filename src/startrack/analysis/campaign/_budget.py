"""Error budgets: ``[campaign] mode = "budget"`` switches error sources on one at a time.

The image level renders, detects and solves frames; a budget runs the scenario of ``[base]``
(with each ``[[budget.case]]``'s changes, one budget per case) in cells: cell 0 the **baseline**,
every source off; cell 1 **all** sources on; then one cell per source with only it on. Each source
(:data:`SOURCES`) names the parameters it sets when off and when on; "off" removes the source
(noise switches off, the true lens given to the solver, the catalog at the scene's epoch, no
aberration, an exact time tag); where an ideal cannot be simulated (a PSF of zero width, the dark
current's noise without the shot noise) ``docs/error_budget.md`` says what stands for it. Every
cell shares its attitudes (``frames_per_attitude`` of :mod:`.levels.image`): trial k looks at star
field k // (R D) in dither k // R mod D, in R repeated frames (``repeats``, ``dithers``), so that a
source's cell is compared with the baseline on the same skies. :mod:`._budget_terms` estimates the
ECSS-E-ST-60-20C terms of a cell (bias, FOV spatial error, pixel spatial error, temporal noise)
from its trials and each source's contribution (its cell against the baseline) are computed by
:mod:`._budget_terms`; the report section and the terminal text are in :mod:`._budget_report`.

``[budget]`` keys (:data:`BUDGET_KEYS`; an unknown key is refused naming it): ``sources``,
``repeats``, ``dithers``, ``dither_px``, the "on" values ``psf_sigma_px``, ``k1``, ``k2``,
``solver_epoch_jyear``, ``aberration_annual``, ``aberration_velocity_km_s``, ``timing_error_s``,
the "off" PSF ``psf_off_sigma_px``, and ``case`` (a list of tables: ``name`` and parameters).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ._params import Param, SpecError
from ._spec import CampaignSpec, Cell
from .levels._scene import frame_camera, frame_sensor

DEFAULT_K1 = 0.01
"""The lens's k1 when the scenario's lens has no distortion and ``[budget] k1`` is not given
(about 0.25 px at the corner of the default 15 deg, 1024 px camera)."""


@dataclass(frozen=True)
class Source:
    """One error source: what it sets off and on (``settings(on, scene, budget) -> parameters``)
    and the two states in words (``words(scene, budget) -> (off, on)``)."""

    name: str
    doc: str
    settings: Callable[[bool, Mapping[str, Any], Mapping[str, Any]], dict[str, Any]]
    words: Callable[[Mapping[str, Any], Mapping[str, Any]], tuple[str, str]]


def _show(values: Any) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"


def _switch(*names: str) -> Callable[[bool, Mapping[str, Any], Mapping[str, Any]], dict[str, Any]]:
    return lambda on, scene, budget: {name: on for name in names}


def _psf_on(scene: Mapping[str, Any], budget: Mapping[str, Any]) -> float:
    value = budget["psf_sigma_px"]
    return float(frame_sensor(scene).optics.psf_sigma_px) if value is None else value


def _lens(scene: Mapping[str, Any], budget: Mapping[str, Any]) -> dict[str, float]:
    """The true lens of every cell: [budget] k1, k2, else the scenario's (DEFAULT_K1 for a pinhole)."""
    camera = frame_camera(scene)
    k1 = camera.k1 if budget["k1"] is None else budget["k1"]
    k2 = camera.k2 if budget["k2"] is None else budget["k2"]
    if budget["k1"] is None and budget["k2"] is None and k1 == 0.0 and k2 == 0.0:
        k1 = DEFAULT_K1
    return {"k1": float(k1), "k2": float(k2)}


def _noise_words(what: str) -> Callable[[Mapping[str, Any], Mapping[str, Any]], tuple[str, str]]:
    return lambda scene, budget: (f"no {what}", f"{what} of the scenario's sensor")


def _read_words(scene: Mapping[str, Any], budget: Mapping[str, Any]) -> tuple[str, str]:
    return "no read noise", f"read noise {frame_sensor(scene).detector.read_noise_e:g} e- rms"


def _dark_words(scene: Mapping[str, Any], budget: Mapping[str, Any]) -> tuple[str, str]:
    sensor = frame_sensor(scene)
    return ("no dark charge", f"dark current {sensor.detector.dark_current_e_s:g} e-/s x {sensor.exposure_s:g} s "
            "with its fixed pattern; without shot noise its Poisson noise is a Gaussian of the same variance")


SOURCES: dict[str, Source] = {s.name: s for s in (
    Source("shot_noise", "Poisson noise of the star light, sky and dark charge", _switch("noise_shot"),
           _noise_words("shot noise")),
    Source("read_noise", "Gaussian read noise", _switch("noise_read"), _read_words),
    Source("dark_current", "dark charge, its noise and fixed pattern (DSNU, hot pixels)",
           _switch("noise_dark", "noise_dsnu", "noise_hot_pixels"), _dark_words),
    Source("psf_width", "the width of the point-spread function",
           lambda on, scene, budget: {"psf_sigma_px": _psf_on(scene, budget) if on else budget["psf_off_sigma_px"]},
           lambda scene, budget: (f"PSF sigma {budget['psf_off_sigma_px']:g} px (a focused spot)",
                                  f"PSF sigma {_psf_on(scene, budget):g} px")),
    Source("quantisation", "rounding to whole ADU, the ADC's range and the full well",
           _switch("noise_quantize", "noise_saturate"),
           lambda scene, budget: ("unquantised ADU, no saturation",
                                  f"{frame_sensor(scene).detector.bit_depth}-bit ADC, rounded and clipped, "
                                  f"full well {frame_sensor(scene).detector.full_well_e:g} e-")),
    Source("distortion", "the lens's radial distortion left uncalibrated",
           lambda on, scene, budget: {"distortion_known": not on},
           lambda scene, budget: ("the solver has the true lens", "the solver assumes k1 = k2 = 0 for a lens with "
                                  + ", ".join(f"{k} = {v:g}" for k, v in _lens(scene, budget).items()))),
    Source("proper_motion", "the catalog's stars not moved to the scene's epoch",
           lambda on, scene, budget: {"solver_epoch_jyear": budget["solver_epoch_jyear"] if on else None},
           lambda scene, budget: (f"catalog at the scene's epoch {scene['epoch_jyear']:g}",
                                  f"catalog at {budget['solver_epoch_jyear']:g}, scene at {scene['epoch_jyear']:g}")),
    Source("aberration", "stellar aberration the solver does not correct",
           lambda on, scene, budget: {"aberration_annual": on and budget["aberration_annual"],
                                      "aberration_velocity_km_s": budget["aberration_velocity_km_s"] if on
                                      else (0.0, 0.0, 0.0)},
           lambda scene, budget: ("no aberration", ("annual aberration + " if budget["aberration_annual"] else "")
                                  + f"spacecraft velocity {_show(budget['aberration_velocity_km_s'])} km/s (GCRS)")),
    Source("timing", "an error of the frame's time tag, at the scenario's rate",
           lambda on, scene, budget: {"timing_error_s": budget["timing_error_s"] if on else 0.0},
           lambda scene, budget: ("exact time tag", f"time tag off by {budget['timing_error_s']:g} s at "
                                  f"{_show(scene['rate_deg_s'])} deg/s")),
)}
"""The error sources, in their default order."""

BUDGET_KEYS: dict[str, Param] = {p.name: p for p in (
    Param("sources", "str", None, "the sources to budget (a list; default all): " + ", ".join(SOURCES)),
    Param("repeats", "int", 3, "frames per attitude, with independent noise (temporal noise)", lo=1, hi=10_000),
    Param("dithers", "int", 2, "dithered attitudes per star field (pixel spatial error)", lo=1, hi=10_000),
    Param("dither_px", "float", 1.0, "width of the dither square (px; 1 covers every pixel phase)", lo=0.0, hi=100.0),
    Param("psf_sigma_px", "float", None, "PSF sigma with psf_width on (px); auto: the scenario's", lo=0.05, hi=50.0,
          optional=True),
    Param("psf_off_sigma_px", "float", 0.8, "PSF sigma with psf_width off (px): a focused, well-sampled spot",
          lo=0.05, hi=50.0),
    Param("k1", "float", None, f"the lens's k1 (every cell); auto: the scenario's, {DEFAULT_K1:g} for a pinhole",
          lo=-5.0, hi=5.0, optional=True),
    Param("k2", "float", None, "the lens's k2 (every cell); auto: the scenario's", lo=-5.0, hi=5.0, optional=True),
    Param("solver_epoch_jyear", "float", 1991.25, "catalog epoch the solver assumes with proper_motion on "
          "(Julian year; 1991.25: Hipparcos as published)", lo=1900.0, hi=2100.0),
    Param("aberration_annual", "bool", True, "aberration on includes the Earth's annual aberration"),
    Param("aberration_velocity_km_s", "floats", (0.0, 0.0, 0.0), "aberration on: the spacecraft's velocity "
          "about the geocentre (GCRS axes, km/s)", lo=-1000.0, hi=1000.0, length=3),
    Param("timing_error_s", "float", 0.01, "time-tag error with timing on (s)", lo=-100.0, hi=100.0),
)}

OWNED = ("noise_shot", "noise_read", "noise_dark", "noise_dsnu", "noise_hot_pixels", "noise_quantize", "noise_saturate",
         "calibrated",
         "distortion_known", "solver_epoch_jyear", "aberration_annual", "aberration_velocity_km_s", "timing_error_s",
         "frames_per_attitude", "attitudes_per_field", "dither_px")
"""Image-level parameters the budget sets in every cell (refused in ``[base]`` and in a case)."""


def budget_settings(spec: CampaignSpec) -> dict[str, Any]:
    """The checked ``[budget]`` table with defaults filled (``sources`` a tuple of names,
    ``case`` a list of (name, parameters)).

    Raises
    ------
    SpecError
        For an unknown key, a bad value, an unknown source, a bad case, a parameter the budget sets
        given in ``[base]``, a ``[sweep]``, or trials that are not whole star fields.
    """
    if spec.level != "image":
        raise SpecError(f'[campaign] mode = "budget" runs on level "image", not {spec.level!r}')
    if spec.sweep:
        raise SpecError("[sweep] is not read in budget mode: give one [[budget.case]] per scenario instead")
    table = dict(spec.budget)
    cases = table.pop("case", [{"name": "base"}])
    unknown = sorted(set(table) - set(BUDGET_KEYS))
    if unknown:
        raise SpecError(f"[budget] {unknown[0]}: unknown key; valid: {', '.join([*BUDGET_KEYS, 'case'])}")
    out = {key: p.default for key, p in BUDGET_KEYS.items()}
    out.update({key: BUDGET_KEYS[key].check(v, "[budget]") for key, v in table.items() if key != "sources"})
    out["sources"] = _sources(table.get("sources", list(SOURCES)))
    out["case"] = _cases(spec, cases)
    _owned(spec.base, "[base]")
    per_field = out["repeats"] * out["dithers"]
    if spec.trials % per_field:
        raise SpecError(f"[campaign] trials = {spec.trials} must be whole star fields: a multiple of [budget] "
                        f"repeats x dithers = {out['repeats']} x {out['dithers']} = {per_field}")
    return out


def _sources(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise SpecError(f"[budget] sources: must be a non-empty list of source names, got {value!r}; "
                        f"valid: {', '.join(SOURCES)}")
    for name in value:
        if name not in SOURCES:
            raise SpecError(f"[budget] sources: unknown source {name!r}; valid: {', '.join(SOURCES)}")
    if len(set(value)) != len(value):
        raise SpecError(f"[budget] sources: repeats a source ({value!r})")
    return tuple(value)


def _owned(table: Mapping[str, Any], where: str) -> None:
    for key in table:
        if key in OWNED:
            raise SpecError(f"{where} {key}: set by the budget in every cell; give the source's 'on' value in "
                            f"[budget] ({', '.join(k for k in BUDGET_KEYS if k not in ('sources',))})")


def _cases(spec: CampaignSpec, cases: Any) -> list[tuple[str, dict[str, Any]]]:
    if not isinstance(cases, list) or not cases or not all(isinstance(c, dict) for c in cases):
        raise SpecError("[budget] case: must be a list of tables (write each as [[budget.case]] with a name)")
    params = spec.level_def.params
    out: list[tuple[str, dict[str, Any]]] = []
    for i, case in enumerate(cases):
        name = case.get("name")
        if not isinstance(name, str) or not name or name in (n for n, _ in out):
            raise SpecError(f"[[budget.case]] {i}: needs a name of its own (a non-empty string), got {name!r}")
        where = f"[[budget.case]] {name}"
        changes = {k: v for k, v in case.items() if k != "name"}
        _owned(changes, where)
        for key in changes:
            if key not in params:
                raise SpecError(f"{where} {key}: unknown parameter of this level; valid: {', '.join(params)}")
        out.append((name, {k: params[k].check(v, where) for k, v in changes.items()}))
    return out


def cell_params(scene: Mapping[str, Any], budget: Mapping[str, Any], on: frozenset[str]) -> dict[str, Any]:
    """The parameters of the cell of ``scene`` with the sources ``on`` (every other source off)."""
    params = {**scene, **_lens(scene, budget), "calibrated": True, "frames_per_attitude": budget["repeats"],
              "attitudes_per_field": budget["dithers"], "dither_px": budget["dither_px"]}
    for name in SOURCES:
        params.update(SOURCES[name].settings(name in on, scene, budget))
    if "dark_current" in on and "shot_noise" not in on:
        # the dark charge's Poisson noise without shot noise: a Gaussian of the same variance
        sensor = frame_sensor(scene)
        read = sensor.detector.read_noise_e if "read_noise" in on else 0.0
        dark_e = sensor.detector.dark_current_e_s * sensor.exposure_s
        params.update(noise_read=bool(read or dark_e), read_noise_e=math.sqrt(read * read + dark_e))
    return params


def budget_cells(spec: CampaignSpec) -> list[Cell]:
    """Per case: the baseline (every source off), all on, then each source alone (``Cell.source``
    ``"baseline"``, ``"all"`` or the source's name; the label adds the case's name when there are
    several)."""
    budget = budget_settings(spec)
    defaults = {name: p.default for name, p in spec.level_def.params.items()}
    several = len(budget["case"]) > 1
    cells: list[Cell] = []
    for case, changes in budget["case"]:
        scene = {**defaults, **spec.base, **changes}
        plan = [("baseline", frozenset()), ("all", frozenset(budget["sources"]))]
        plan += [(name, frozenset((name,))) for name in budget["sources"]]
        for source, on in plan:
            label = f"{case}: {source}" if several else source
            cells.append(Cell(len(cells), cell_params(scene, budget, on), label, source))
    return cells


def budget_manifest(spec: CampaignSpec, cells: list[Cell]) -> dict[str, Any]:
    """The manifest's ``budget``: sources, the first case's ``baseline`` and ``all`` cells, every
    case's cells, the design (repeats, dithers, fields) and what off and on mean per source."""
    budget = budget_settings(spec)
    defaults = {name: p.default for name, p in spec.level_def.params.items()}
    per_case = 2 + len(budget["sources"])
    cases = []
    for i, (name, changes) in enumerate(budget["case"]):
        scene = {**defaults, **spec.base, **changes}
        first = i * per_case
        words = {s: SOURCES[s].words(scene, budget) for s in budget["sources"]}
        cases.append({"name": name, "baseline": first, "all": first + 1,
                      "sources": {s: first + 2 + j for j, s in enumerate(budget["sources"])},
                      "off": {s: w[0] for s, w in words.items()}, "on": {s: w[1] for s, w in words.items()}})
    return {"sources": list(budget["sources"]), "baseline": 0, "all": 1, "cases": cases,
            "repeats": budget["repeats"], "dithers": budget["dithers"], "dither_px": budget["dither_px"],
            "fields": spec.trials // (budget["repeats"] * budget["dithers"]),
            "doc": {s: SOURCES[s].doc for s in budget["sources"]}}


from . import _budget_report as budget_report  # noqa: E402,F401  (registers the report section)
