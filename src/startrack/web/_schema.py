"""The OpenAPI 3.1 document of the JSON API, written out by hand (no framework generates it).

Each operation lists its parameters, request body and the responses it can give, refusals
included (see :mod:`._refusals` for what each status means).
"""

from __future__ import annotations

from typing import Any

from .. import __version__

_ERROR = {"$ref": "#/components/schemas/Error"}
_ID = {"name": "job_id", "in": "path", "required": True, "schema": {"type": "string", "pattern": "^[0-9a-f]{32}$"}}
_BATCH = {**_ID, "name": "batch_id"}
_NAME = {"name": "name", "in": "path", "required": True,
         "schema": {"type": "string", "examples": ["annotated.png", "solution.wcs", "matches.csv"]}}
_MULTIPART_JOB = {"multipart/form-data": {"schema": {"type": "object", "properties": {
    "file": {"type": "string", "format": "binary",
             "description": "FITS, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP or camera RAW"},
    "options": {"type": "string", "description": "JSON object of solve options (docs/web.md)"},
    "simulate": {"type": "string", "description": "JSON object of scene parameters, instead of a file"}}}}}
_MULTIPART_BATCH = {"multipart/form-data": {"schema": {"type": "object", "properties": {
    "file": {"type": "array", "items": {"type": "string", "format": "binary"}},
    "folder": {"type": "string", "description": "a folder relative to --root, instead of files"},
    "name": {"type": "string"}, "options": {"type": "string"}}}}}
_ANALYSIS = {"application/json": {"schema": {"type": "object", "required": ["analysis", "sets"], "properties": {
    "analysis": {"type": "string"}, "params": {"type": "object"},
    "sets": {"type": "array", "items": {"type": "object", "description": "{batch: id} or {name, jobs: [id, ...]}"}}}}}}

OPERATIONS: tuple[tuple[str, str, str, list, dict | None, dict[int, str]], ...] = (
    ("/api/status", "get", "Server version, workers and queue", [], None, {200: "status"}),
    ("/api/options", "get", "What the upload page offers", [], None, {200: "presets, cameras, sites, methods"}),
    ("/api/jobs", "post", "Submit one image (or a scene to simulate)", [], _MULTIPART_JOB,
     {201: "{id, state: queued}", 400: "not one file part", 413: "body over --max-upload-mb",
      415: "not multipart, or not an image by its content", 422: "bad option or absurd dimensions",
      429: "queue full"}),
    ("/api/jobs", "get", "Every job, newest first", [{"name": "state", "in": "query", "schema": {"type": "string"}}],
     None, {200: "{jobs, count}"}),
    ("/api/jobs/{job_id}", "get", "One job: state, stage, progress, error, result, files", [_ID], None,
     {200: "the job", 404: "no such job"}),
    ("/api/jobs/{job_id}", "delete", "Cancel a queued or running job, or remove a finished one", [_ID], None,
     {200: "{id, state} or {id, deleted}", 404: "no such job"}),
    ("/api/jobs/{job_id}/files/{name}", "get", "A result file of a job", [_ID, _NAME], None,
     {200: "the file", 206: "the byte ranges a Range header asks",
      304: "the client's copy is current (If-None-Match, If-Modified-Since)", 404: "no such job or file",
      416: "no byte of the Range header's ranges lies in the file"}),
    ("/api/batches", "post", "Several images (or a folder under --root) as one result set", [], _MULTIPART_BATCH,
     {201: "{id, jobs, state}", 404: "folder not under --root", 413: "too large", 415: "not an image",
      422: "bad option", 429: "queue full"}),
    ("/api/batches", "get", "Every batch", [], None, {200: "{batches}"}),
    ("/api/batches/{batch_id}", "get", "One batch and its jobs", [_BATCH], None, {200: "the batch", 404: "none"}),
    ("/api/analyses", "get", "The post-processing analyses", [], None, {200: "{analyses}"}),
    ("/api/analyses", "post", "Run an analysis over result sets", [], _ANALYSIS,
     {201: "{id, state: queued}", 404: "no such job or batch", 409: "a job not finished",
      422: "bad analysis, sets or params", 429: "queue full"}),
    ("/api/cameras", "get", "Camera presets and saved profiles", [], None, {200: "{cameras}"}),
    ("/api/cameras", "post", "Save a camera profile", [], {"application/json": {"schema": {"type": "object"}}},
     {201: "{name, camera}", 422: "bad profile"}),
    ("/api/openapi.json", "get", "This document", [], None, {200: "OpenAPI 3.1"}),
)


def _operation(summary: str, params: list, body: dict | None, responses: dict[int, str]) -> dict[str, Any]:
    out: dict[str, Any] = {"summary": summary, "parameters": params, "responses": {
        str(code): {"description": text, **({"content": {"application/json": {"schema": _ERROR}}} if code >= 400
                                            else {})} for code, text in responses.items()}}
    if body is not None:
        out["requestBody"] = {"required": True, "content": body}
    return out


def openapi_document() -> dict[str, Any]:
    """The OpenAPI document (a plain dict, served as JSON)."""
    paths: dict[str, dict[str, Any]] = {}
    for path, method, summary, params, body, responses in OPERATIONS:
        paths.setdefault(path, {})[method] = _operation(summary, params, body, responses)
    return {"openapi": "3.1.0",
            "info": {"title": "startrack web", "version": __version__,
                     "description": "Local star-image solving and analysis; see docs/web.md."},
            "paths": paths,
            "components": {"schemas": {"Error": {"type": "object", "required": ["error"], "properties": {
                "error": {"type": "string"}, "field": {"type": "string"}}}}}}
