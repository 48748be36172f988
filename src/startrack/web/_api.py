"""The JSON API (every page has its twin here; the OpenAPI document is ``/api/openapi.json``).

=======================================  ====================================================
``GET /api/status``                      version, workers, queue
``GET /api/options``                     what the upload page offers: presets, cameras, sites,
                                         methods, analyses, limits
``POST /api/jobs``                       multipart: ``file`` + optional ``options`` (JSON), or
                                         ``simulate`` (JSON) without a file -> 201 ``{id, state}``
``GET /api/jobs``                        every job, newest first (``?state=done`` filters)
``GET /api/jobs/{id}``                   state, stage, progress, error, result, files
``GET /api/jobs/{id}/files/{name}``      a result file (byte ranges, :mod:`._ranges`; 304 for a
                                         current copy, :mod:`._conditional`)
``DELETE /api/jobs/{id}``                cancel a queued or running job; remove a finished one
``POST /api/batches``                    multipart: several ``file`` parts, or ``folder`` (under
                                         ``--root``); optional ``options``, ``name``
``GET /api/batches``, ``/api/batches/{id}``  result sets
``GET /api/analyses``                    the post-processing analyses and their parameters
``POST /api/analyses``                   JSON ``{analysis, sets, params}`` -> 201 ``{id, state}``
``GET /api/cameras``, ``POST /api/cameras``  camera profiles
=======================================  ====================================================
"""

from __future__ import annotations

from typing import Any

from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Route

from .. import __version__
from . import _json_text as json_text
from ._conditional import not_modified
from ._jobs import STATES
from ._options import OptionError, parse_options
from ._ranges import settle_range
from ._refusals import Refusal, not_found
from ._schema import openapi_document
from ._service import Service, option_refusal
from ._uploads import read_form
from ._views import options_view

CONTENT_TYPES = {".png": "image/png", ".json": "application/json", ".csv": "text/csv",
                 ".wcs": "application/fits"}
MAX_JSON_BYTES = 65_536


def service_of(request: Request) -> Service:
    return request.app.state.service


def _first(fields: dict[str, list[str]], name: str) -> str | None:
    """The first value of a form field, None if the form has none."""
    values = fields.get(name)
    return values[0] if values else None


def options_of(fields: dict[str, list[str]], service: Service) -> dict[str, Any]:
    """The checked ``options`` field (422 naming the bad option)."""
    try:
        return parse_options(_first(fields, "options"), service.config.cameras_dir)
    except OptionError as exc:
        raise option_refusal(exc) from None


async def json_body(request: Request) -> Any:
    """The request's JSON body (415 unless JSON, 413 when too large, 400 when malformed)."""
    if not request.headers.get("content-type", "").lower().startswith("application/json"):  # media types: any case
        raise Refusal(415, "send a JSON body with Content-Type: application/json")
    body = b""
    async for chunk in request.stream():
        body += chunk
        if len(body) > MAX_JSON_BYTES:
            raise Refusal(413, f"the JSON body is larger than {MAX_JSON_BYTES} bytes")
    try:
        return json_text.loads(body)
    except ValueError as exc:
        raise Refusal(400, f"the body is not valid JSON ({exc})") from None


async def status(request: Request) -> JSONResponse:
    service = service_of(request)
    return JSONResponse({"version": __version__, **service.pool.info(),
                         "max_upload_mb": service.config.max_upload_mb, "folder_mode": service.config.root is not None})


async def get_options(request: Request) -> JSONResponse:
    return JSONResponse(options_view(service_of(request)))


async def post_job(request: Request) -> JSONResponse:
    service = service_of(request)
    service.check_room()
    fields, files = await read_form(request, service.config.max_upload_bytes)
    try:
        options = options_of(fields, service)
        if not files and fields.get("simulate"):
            data = service.create_simulated(_json_field(fields, "simulate"), options)
        elif len(files) != 1:
            raise Refusal(400, f"send exactly one 'file' part (got {len(files)}); POST /api/batches takes several")
        else:
            data = await service.create_job(files[0], options)
    finally:
        for upload in files:
            upload.file.close()
    return JSONResponse(data, 201, headers={"Location": f"/api/jobs/{data['id']}"})


def _json_field(fields: dict[str, list[str]], name: str) -> Any:
    try:
        return json_text.loads(fields[name][0])
    except ValueError as exc:
        raise Refusal(422, f"{name} is not valid JSON ({exc})", name) from None


async def list_jobs(request: Request) -> JSONResponse:
    service = service_of(request)
    asked = request.query_params.getlist("state")
    if len(asked) > 1:
        given = ", ".join(repr(a[:40]) for a in asked[:5])
        raise Refusal(400, f"state is given {len(asked)} times ({given}); give one of {', '.join(STATES)}, "
                           "or none for every job", "state")
    wanted = asked[0] if asked else None
    if wanted and wanted not in STATES:
        raise Refusal(400, f"no job state {wanted!r}; valid states: {', '.join(STATES)}", "state")
    jobs = [service.job_summary(j) for j in reversed(service.jobs.ids())]
    if wanted:
        jobs = [j for j in jobs if j["state"] == wanted]
    return JSONResponse({"jobs": jobs, "count": len(jobs)})


async def get_job(request: Request) -> JSONResponse:
    return JSONResponse(service_of(request).job_view(request.path_params["job_id"]))


async def get_file(request: Request) -> Response:
    service = service_of(request)
    path = service.jobs.file_path(request.path_params["job_id"], request.path_params["name"])
    try:
        stat = path.stat()
    except FileNotFoundError:  # deleted since it was listed
        raise not_found(f"job {request.path_params['job_id']} has no file {path.name!r}") from None
    response = FileResponse(path, media_type=CONTENT_TYPES.get(path.suffix, "application/octet-stream"),
                            filename=path.name, stat_result=stat,
                            content_disposition_type="inline" if path.suffix == ".png" else "attachment")
    etag, modified = (response.headers.get(k, "") for k in ("etag", "last-modified"))
    if not_modified(request.headers, etag, modified):  # the router lets GET and HEAD in only
        return Response(status_code=304, headers={"ETag": etag, "Last-Modified": modified})
    settle_range(request.scope, stat.st_size, (etag, modified), path.name)
    return response


async def delete_job(request: Request) -> JSONResponse:
    return JSONResponse(service_of(request).cancel_or_remove(request.path_params["job_id"]))


async def post_batch(request: Request) -> JSONResponse:
    service = service_of(request)
    service.check_room()
    fields, files = await read_form(request, service.config.max_upload_bytes)
    try:
        options = options_of(fields, service)
        name = _first(fields, "name")
        if fields.get("folder") and not files:
            data = await service.create_folder_batch(fields["folder"][0], options, name)
        else:
            data = await service.create_batch(files, options, name)
    finally:
        for upload in files:
            upload.file.close()
    return JSONResponse(data, 201, headers={"Location": f"/api/batches/{data['id']}"})


async def list_batches(request: Request) -> JSONResponse:
    service = service_of(request)
    batches = [service.batch_view(b) for b in reversed(service.batches.ids())]
    return JSONResponse({"batches": [{k: b[k] for k in ("id", "name", "created", "counts", "finished", "page")}
                                     | {"n_jobs": len(b["jobs"])} for b in batches]})


async def get_batch(request: Request) -> JSONResponse:
    return JSONResponse(service_of(request).batch_view(request.path_params["batch_id"]))


async def list_analyses(request: Request) -> JSONResponse:
    return JSONResponse({"analyses": options_view(service_of(request))["analyses"]})


async def post_analysis(request: Request) -> JSONResponse:
    data = service_of(request).create_analysis(await json_body(request))
    return JSONResponse(data, 201, headers={"Location": f"/api/jobs/{data['id']}"})


async def list_cameras(request: Request) -> JSONResponse:
    return JSONResponse({"cameras": options_view(service_of(request))["cameras"]})


async def post_camera(request: Request) -> JSONResponse:
    return JSONResponse(service_of(request).save_camera(await json_body(request)), 201)


async def openapi(request: Request) -> JSONResponse:
    return JSONResponse(openapi_document())


ROUTES = [
    Route("/api/status", status), Route("/api/options", get_options), Route("/api/openapi.json", openapi),
    Route("/api/jobs", post_job, methods=["POST"]), Route("/api/jobs", list_jobs, methods=["GET"]),
    Route("/api/jobs/{job_id}", get_job, methods=["GET"]), Route("/api/jobs/{job_id}", delete_job, methods=["DELETE"]),
    Route("/api/jobs/{job_id}/files/{name}", get_file),
    Route("/api/batches", post_batch, methods=["POST"]), Route("/api/batches", list_batches, methods=["GET"]),
    Route("/api/batches/{batch_id}", get_batch),
    Route("/api/analyses", list_analyses, methods=["GET"]), Route("/api/analyses", post_analysis, methods=["POST"]),
    Route("/api/cameras", list_cameras, methods=["GET"]), Route("/api/cameras", post_camera, methods=["POST"]),
]
