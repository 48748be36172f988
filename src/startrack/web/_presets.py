"""Detection presets, named sets of :class:`~startrack.detect.StarDetector` settings, and ``auto``.

A preset is a starting point: settings given in the job's ``detection`` object override it. The
``auto`` preset looks at the image first (:func:`auto_settings`): a probe detection with seed
000 §8.2.3's dynamic threshold (the lowest k >= :data:`AUTO_MIN_SIGMA` that leaves
:data:`AUTO_TARGET_SPOTS` spots) gives the threshold, and the median PSF width of the brightest
spots the minimum area (half the area of the 1-sigma disc, 2 to 9 px). It also turns on
``fit_camera``: the focal length (hence the FOV) and the lens distortion are fitted on the stars of
a trial solve and the image is solved again with that camera (the ``refine`` stage of
:mod:`._pipeline`, with :mod:`startrack.calibrate._selfcal`'s fit and F-test).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..detect import StarDetector


@dataclass(frozen=True)
class DetectionPreset:
    """A named set of detector settings with a sentence saying what it is for."""

    name: str
    description: str
    settings: Mapping[str, Any] = field(default_factory=dict)


PRESETS: dict[str, DetectionPreset] = {p.name: p for p in (
    DetectionPreset("default", "the detector's defaults: 5-sigma threshold, spots of 4 px or more"),
    DetectionPreset("faint", "more stars from a low-signal frame: 3.5-sigma, spots of 3 px or more",
                    {"sigma": 3.5, "min_area_px": 3}),
    DetectionPreset("bright", "only clear stars: 8-sigma, spots of 6 px or more", {"sigma": 8.0, "min_area_px": 6}),
    DetectionPreset("dynamic", "Huffman 2006 §8.2.3's dynamic threshold: the lowest k >= 5 that leaves 30 spots",
                    {"threshold": "dynamic", "target_stars": 30}),
    DetectionPreset("cluttered", "ground photos with trees or roofs: stricter elongation and clutter tests",
                    {"max_elongation": 3.0, "max_clutter": 1.8}),
    DetectionPreset("auto", "threshold and minimum area from the image; focal length and distortion fitted "
                            "on a trial solve"),
)}
AUTO_TARGET_SPOTS = 40
AUTO_MIN_SIGMA = 4.0
AUTO_MAX_SIGMA = 50.0
AUTO_PSF_SPOTS = 10
"""The brightest spots whose PSF width sets the minimum area."""


def preset_detector(name: str, overrides: Mapping[str, Any]) -> StarDetector:
    """The detector of preset ``name`` (not ``auto``) with ``overrides`` applied."""
    return StarDetector(**{**PRESETS[name].settings, **overrides})


def auto_settings(image: NDArray, overrides: Mapping[str, Any]) -> dict[str, Any]:
    """Threshold (``sigma``) and ``min_area_px`` for ``image`` (module docstring).

    Parameters
    ----------
    image : ndarray, shape (H, W)
        The pixels (counts).
    overrides : mapping
        The job's own detection settings; those it names are kept as given.

    Returns
    -------
    dict
        ``sigma``, ``min_area_px`` (the settings chosen), ``psf_sigma_px`` (median width of the
        brightest probe spots, px) and ``probe_spots`` (spots the probe found).
    """
    probe = StarDetector(**{**overrides, "threshold": "dynamic", "sigma": AUTO_MIN_SIGMA,
                            "target_stars": AUTO_TARGET_SPOTS, "min_area_px": 2}).detect_details(image)
    widths = probe.psf_sigma_px[:AUTO_PSF_SPOTS]
    widths = widths[np.isfinite(widths)]
    psf = float(np.median(widths)) if widths.size else 1.0
    k = float(np.clip(probe.k_sigma if math.isfinite(probe.k_sigma) else AUTO_MIN_SIGMA,
                      AUTO_MIN_SIGMA, AUTO_MAX_SIGMA))
    min_area = int(np.clip(round(0.5 * math.pi * psf**2), 2, 9))
    return {"sigma": k, "min_area_px": min_area, "psf_sigma_px": psf, "probe_spots": len(probe)}


def presets_json() -> list[dict[str, Any]]:
    """The presets for the API and the upload page."""
    return [{"name": p.name, "description": p.description, "settings": dict(p.settings)} for p in PRESETS.values()]
