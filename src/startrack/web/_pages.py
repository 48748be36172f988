"""The HTML pages, rendered on the server (Jinja2); each names its JSON twin.

=====================  ================================  ========================================
page                   what                              JSON twin
=====================  ================================  ========================================
``/``                  upload: files, a folder, simulate  ``/api/options``
``/jobs``              every job                          ``/api/jobs``
``/jobs/{id}``         live progress, annotated frame,    ``/api/jobs/{id}``
                       numbers, downloads
``/batches``           result sets                        ``/api/batches``
``/batches/{id}``      a result set's jobs                ``/api/batches/{id}``
``/analyses``          post-processing form               ``/api/analyses``
``/api``               the endpoints                      ``/api/openapi.json``
=====================  ================================  ========================================

The forms post to ``/upload``, ``/simulate``, ``/analyses``, ``/jobs/{id}/cancel`` and
``/jobs/{id}/remove``, which do what the API does and answer with a redirect (303) to the new
job's or set's page, so the pages work without JavaScript (which only adds live progress and
zoom). Their fields are turned into the API's JSON here (:func:`form_options`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from starlette.requests import Request
from starlette.responses import HTMLResponse, RedirectResponse
from starlette.routing import Route
from starlette.templating import Jinja2Templates

from .. import __version__
from ..io import describe_mosaic
from ._api import service_of
from ._jobs import ANALYSIS_STAGES, SOLVE_STAGES
from ._json_text import MAX_INT_DIGITS
from ._options import OptionError, validate_options
from ._refusals import Refusal
from ._schema import openapi_document
from ._service import option_refusal
from ._uploads import read_form
from ._views import analyses_view, options_view

TEMPLATES = Jinja2Templates(directory=str(Path(__file__).parent / "templates"))
TEMPLATES.env.globals["version"] = __version__
TEMPLATES.env.filters["mosaic_words"] = describe_mosaic


def _significant(value: Any, digits: int = 6) -> str:
    """A number to ``digits`` significant figures for the pages (text and ints unchanged)."""
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return "" if value is None else str(value)


TEMPLATES.env.filters["sig"] = _significant


def render(request: Request, name: str, status_code: int = 200, **context: Any) -> HTMLResponse:
    return TEMPLATES.TemplateResponse(request, name, context, status_code=status_code)


def _last(fields: dict[str, list[str]], key: str) -> str:
    return (fields.get(key) or [""])[-1].strip()


def _number(fields: dict[str, list[str]], key: str, kind: type = float) -> float | int | None:
    text = _last(fields, key)
    if not text:
        return None
    what = "a whole number" if kind is int else "a number"
    try:
        value = kind(text)
    except ValueError:
        raise OptionError(f"options.{key}", f"must be {what}, got {text!r}") from None
    if kind is int and len(str(abs(value))) > MAX_INT_DIGITS:  # as the API's JSON reads it (._json_text)
        raise OptionError(f"options.{key}", f"must be {what} of at most {MAX_INT_DIGITS} digits, got {text[:24]!r}...")
    return value


def form_options(fields: dict[str, list[str]]) -> dict[str, Any]:
    """The options JSON of the upload form's fields (``options_fields.html``), unchecked."""
    out: dict[str, Any] = {}
    mode = _last(fields, "fov_mode") or "search"
    if mode == "fov":
        out["fov_deg"] = _number(fields, "fov_deg")
    elif mode == "range":
        out["fov_range_deg"] = [_number(fields, "fov_lo"), _number(fields, "fov_hi")]
    elif mode == "camera":
        out["camera"] = _last(fields, "camera") or None
    for key in ("time", "site", "method", "channel", "detection_preset"):
        if _last(fields, key):
            out[key] = _last(fields, key)
    for key in ("utc_offset_hours", "latitude_deg", "longitude_deg", "height_m"):
        out[key] = _number(fields, key)
    out["lens_correction"] = "lens_correction" in fields
    out["atmosphere_correction"] = "atmosphere_correction" in fields
    for key in ("fit_camera", "guided"):
        if key in fields:
            out[key] = True
    detection = {"sigma": _number(fields, "sigma"), "min_area_px": _number(fields, "min_area_px", int)}
    out["detection"] = {k: v for k, v in detection.items() if v is not None}
    return {k: v for k, v in out.items() if v is not None}


def _checked_form_options(fields: dict[str, list[str]], request: Request) -> dict[str, Any]:
    try:
        return validate_options(form_options(fields), service_of(request).config.cameras_dir)
    except OptionError as exc:
        raise option_refusal(exc) from None


async def index(request: Request) -> HTMLResponse:
    return render(request, "index.html", nav="upload", twin="/api/options", options=options_view(service_of(request)))


async def upload(request: Request) -> RedirectResponse:
    service = service_of(request)
    service.check_room()
    fields, files = await read_form(request, service.config.max_upload_bytes)
    try:
        options = _checked_form_options(fields, request)
        name = _last(fields, "name") or None
        files = [f for f in files if f.filename]  # an empty file input sends one nameless part
        if _last(fields, "folder") and not files:
            data = await service.create_folder_batch(_last(fields, "folder"), options, name)
        elif len(files) == 1:
            data = await service.create_job(files[0], options)
            return RedirectResponse(f"/jobs/{data['id']}", 303)
        else:
            data = await service.create_batch(files, options, name)
    finally:
        for upload_file in files:
            upload_file.file.close()
    return RedirectResponse(f"/batches/{data['id']}", 303)


async def simulate(request: Request) -> RedirectResponse:
    service = service_of(request)
    service.check_room()
    fields, files = await read_form(request, service.config.max_upload_bytes)
    for upload_file in files:
        upload_file.file.close()
    scene = {"fov_deg": _number(fields, "sim_fov_deg"), "width": _number(fields, "sim_width", int),
             "height": _number(fields, "sim_height", int), "max_mag": _number(fields, "sim_max_mag"),
             "seed": _number(fields, "sim_seed", int)}
    options = service.create_simulated(scene, validate_options({}, service.config.cameras_dir))
    return RedirectResponse(f"/jobs/{options['id']}", 303)


async def jobs_page(request: Request) -> HTMLResponse:
    service = service_of(request)
    jobs = [service.job_summary(j) for j in reversed(service.jobs.ids())]
    return render(request, "jobs.html", nav="jobs", twin="/api/jobs", jobs=jobs)


async def job_page(request: Request) -> HTMLResponse:
    job = service_of(request).job_view(request.path_params["job_id"])
    stages = SOLVE_STAGES if job["kind"] == "solve" else ANALYSIS_STAGES
    return render(request, "job.html", nav="jobs", twin=f"/api/jobs/{job['id']}", job=job, stages=stages)


async def cancel_job(request: Request) -> RedirectResponse:
    job_id = request.path_params["job_id"]
    service = service_of(request)
    if service.jobs.state(job_id)["state"] in ("queued", "running"):
        service.pool.cancel(job_id)
    return RedirectResponse(f"/jobs/{job_id}", 303)


async def remove_job(request: Request) -> RedirectResponse:
    service_of(request).cancel_or_remove(request.path_params["job_id"])
    return RedirectResponse("/jobs", 303)


async def batches_page(request: Request) -> HTMLResponse:
    return render(request, "batches.html", nav="batches", twin="/api/batches", batches=_batches(request))


def _batches(request: Request) -> list[dict[str, Any]]:
    service = service_of(request)
    out = []
    for batch_id in reversed(service.batches.ids()):
        view = service.batch_view(batch_id)
        out.append({**view, "n_jobs": len(view["jobs"])})
    return out


async def batch_page(request: Request) -> HTMLResponse:
    batch = service_of(request).batch_view(request.path_params["batch_id"])
    return render(request, "batch.html", nav="batches", twin=f"/api/batches/{batch['id']}", batch=batch)


async def analyses_page(request: Request) -> HTMLResponse:
    batches = [b for b in _batches(request) if b["finished"]]
    selected = {i: request.query_params.get(f"set{i}") for i in range(1, 7)}
    return render(request, "analyses.html", nav="analyses", twin="/api/analyses", analyses=analyses_view(),
                  batches=batches, selected=selected, chosen=request.query_params.get("analysis"))


async def run_analysis_form(request: Request) -> RedirectResponse:
    from ..analysis.postprocess import ANALYSES, parse_param
    from ..errors import InvalidInputError

    service = service_of(request)
    fields, files = await read_form(request, service.config.max_upload_bytes)
    for upload_file in files:
        upload_file.file.close()
    name = _last(fields, "analysis")
    params: dict[str, Any] = {}
    if name in ANALYSES:
        prefix = f"param.{name}."
        for key, values in fields.items():
            if key.startswith(prefix) and values[-1].strip():
                try:
                    params[key.removeprefix(prefix)] = parse_param(ANALYSES[name], key.removeprefix(prefix),
                                                                   values[-1])
                except InvalidInputError as exc:
                    raise Refusal(422, str(exc), "params") from None
    sets = [{"batch": _last(fields, f"set{i}")} for i in range(1, 7) if _last(fields, f"set{i}")]
    data = service.create_analysis({"analysis": name, "sets": sets, "params": params})
    return RedirectResponse(f"/jobs/{data['id']}", 303)


async def api_page(request: Request) -> HTMLResponse:
    return render(request, "api.html", nav="api", twin="/api/openapi.json", doc=openapi_document())


ROUTES = [
    Route("/", index), Route("/upload", upload, methods=["POST"]), Route("/simulate", simulate, methods=["POST"]),
    Route("/jobs", jobs_page), Route("/jobs/{job_id}", job_page),
    Route("/jobs/{job_id}/cancel", cancel_job, methods=["POST"]),
    Route("/jobs/{job_id}/remove", remove_job, methods=["POST"]),
    Route("/batches", batches_page), Route("/batches/{batch_id}", batch_page),
    Route("/analyses", analyses_page, methods=["GET"]), Route("/analyses", run_analysis_form, methods=["POST"]),
    Route("/api", api_page),
]
