"""Read-only views shared by the pages and the API: what the upload and analysis pages offer."""

from __future__ import annotations

from typing import Any

from ..camera import PRESETS as CAMERA_PRESETS
from ..solve import DEFAULT_FOV_RANGE_DEG, MAX_FOV_DEG, MIN_FOV_DEG
from ._batches import list_folders
from ._config import MAX_SIDE_PX, MIN_SIDE_PX
from ._options import KEYS, METHODS, load_camera, profile_names
from ._presets import presets_json
from ._simulation import DEFAULTS as SIMULATION_DEFAULTS


def cameras_view(cameras_dir) -> list[dict[str, Any]]:
    """Presets then saved profiles: name, size, FOV, whether it has a distortion model, source."""
    out = []
    for name, kind in [(n, "preset") for n in sorted(CAMERA_PRESETS)] + [(n, "profile")
                                                                         for n in profile_names(cameras_dir)]:
        camera = load_camera(name, cameras_dir)
        out.append({"name": name, "kind": kind, "width": camera.width, "height": camera.height,
                    "fov_deg": round(camera.fov_deg, 4), "distortion": camera.has_distortion,
                    "source": camera.source})
    return out


def sites_view() -> list[dict[str, Any]]:
    from dataclasses import asdict

    from ..calibrate import load_sites

    return [asdict(site) for site in load_sites().values()]


def analyses_view() -> list[dict[str, Any]]:
    """Every analysis with its parameters (type name, default, help, limits, choices)."""
    from ..analysis.postprocess import ANALYSES

    out = []
    for info in ANALYSES.values():
        params = {key: {"type": kind.__name__, "default": default, "help": text,
                        "limits": info.limits.get(key), "choices": info.choices.get(key)}
                  for key, (kind, default, text) in info.params.items()}
        out.append({"name": info.name, "title": info.title, "description": info.description,
                    "min_sets": info.min_sets, "max_sets": info.max_sets, "needs_images": info.needs_images,
                    "params": params})
    return out


def options_view(service) -> dict[str, Any]:
    """The JSON twin of the upload page (``GET /api/options``)."""
    config = service.config
    return {"options": list(KEYS), "detection_presets": presets_json(), "cameras": cameras_view(config.cameras_dir),
            "sites": sites_view(), "methods": list(METHODS), "analyses": analyses_view(),
            "folders": list_folders(config.root), "simulate_defaults": SIMULATION_DEFAULTS,
            "limits": {"max_upload_mb": config.max_upload_mb, "max_pixels": config.max_pixels,
                       "min_side_px": MIN_SIDE_PX, "max_side_px": MAX_SIDE_PX, "time_limit_s": config.time_limit_s,
                       "max_queued": config.max_queued, "workers": config.workers,
                       "fov_deg": [MIN_FOV_DEG, MAX_FOV_DEG], "default_fov_range_deg": list(DEFAULT_FOV_RANGE_DEG)}}
