"""The Starlette application: routes, refusals as JSON (API) or as a page, the worker pool's life.

The pool starts with the application (the jobs left queued by an earlier server are queued
again; those left running are marked failed) and stops with it. Every response carries
``X-Content-Type-Options: nosniff`` and a content-security policy that allows only this server's
own scripts, styles and images. A state-changing request (POST, DELETE) whose ``Origin`` is
another site is refused with 403, so a web page elsewhere cannot submit jobs to this server
through the user's browser.
"""

from __future__ import annotations

from collections.abc import Mapping
from contextlib import asynccontextmanager
from pathlib import Path
from urllib.parse import urlsplit

from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Mount
from starlette.staticfiles import StaticFiles
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from . import _api as api
from . import _pages as pages
from ._config import WebConfig
from ._jobs import UnknownJobError
from ._options import OptionError
from ._refusals import Refusal
from ._service import Service

SECURITY_HEADERS = [(b"x-content-type-options", b"nosniff"), (b"referrer-policy", b"same-origin"),
                    (b"content-security-policy",
                     b"default-src 'self'; img-src 'self' data:; object-src 'none'; frame-ancestors 'none'")]


class SafetyMiddleware:
    """Security headers on every response; 403 for a cross-site POST or DELETE (module docstring)."""

    def __init__(self, app: ASGIApp):
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        if scope["method"] in ("POST", "PUT", "PATCH", "DELETE") and _cross_site(scope):
            response = JSONResponse({"error": "cross-site request refused: submit from this server's own pages"},
                                    403)
            await response(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                message.setdefault("headers", [])
                message["headers"] = [*message["headers"], *SECURITY_HEADERS]
            await send(message)

        await self.app(scope, receive, with_headers)


def _cross_site(scope: Scope) -> bool:
    headers = {k.decode("latin-1"): v.decode("latin-1") for k, v in scope["headers"]}
    origin = headers.get("origin")
    if not origin or origin == "null":
        return origin == "null"
    return urlsplit(origin).netloc != headers.get("host", "")


def _refusal(request: Request, status: int, message: str, field: str | None = None,
             headers: Mapping[str, str] | None = None) -> Response:
    if request.url.path.startswith("/api"):
        body = {"error": message, **({"field": field} if field else {})}
        return JSONResponse(body, status, headers=headers)
    return pages.render(request, "error.html", status, status=status, message=message, field=field, twin=None)


async def on_refusal(request: Request, exc: Exception) -> Response:
    if isinstance(exc, Refusal):
        return _refusal(request, exc.status, exc.message, exc.field, exc.headers)
    if isinstance(exc, OptionError):
        return _refusal(request, 422, str(exc), exc.field)
    if isinstance(exc, UnknownJobError):
        return _refusal(request, 404, str(exc))
    if isinstance(exc, HTTPException):
        return _refusal(request, exc.status_code, str(exc.detail), headers=exc.headers)
    raise exc


def create_app(config: WebConfig) -> Starlette:
    """The application for ``config`` (its service is ``app.state.service``)."""
    service = Service(config)

    @asynccontextmanager
    async def lifespan(app: Starlette):
        service.start()
        try:
            yield
        finally:
            service.stop()

    static = StaticFiles(directory=str(Path(__file__).parent / "static"))
    app = Starlette(routes=[*api.ROUTES, *pages.ROUTES, Mount("/static", static, name="static")],
                    lifespan=lifespan, middleware=[],
                    exception_handlers={Refusal: on_refusal, OptionError: on_refusal, UnknownJobError: on_refusal,
                                        HTTPException: on_refusal})
    app.state.service = service
    app.add_middleware(SafetyMiddleware)
    return app
