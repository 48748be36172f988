"""Refusals: what the server answers when it will not do what a request asks.

Every refusal is a JSON body ``{"error": "<what is wrong and what would be valid>"}`` (plus
``"field"`` when one field of the request is at fault) with its status code:

===  ==========================================================================================
400  the request is malformed (not multipart, no ``file`` part, broken multipart data)
404  no such job, batch, file or folder (also every malformed id or file name)
409  the job is not in a state that allows it (e.g. the files of an analysis not yet done)
413  the body is larger than ``--max-upload-mb`` (refused while it streams, before it is read)
415  the file's content is not FITS, XISF, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP or camera RAW (sniffed from its bytes)
416  no byte of a result file's ``Range`` header lies in the file (``Content-Range`` gives its size)
422  an option or parameter is invalid, or the image's dimensions are absurd (from its header,
     before decoding); ``field`` names it
429  the queue is full (``Retry-After`` says when to try again)
===  ==========================================================================================
"""

from __future__ import annotations

from typing import Any


class Refusal(Exception):
    """An HTTP refusal (module docstring)."""

    def __init__(self, status: int, message: str, field: str | None = None, headers: dict[str, str] | None = None):
        super().__init__(message)
        self.status, self.message, self.field = status, message, field
        self.headers = headers or {}

    def body(self) -> dict[str, Any]:
        out: dict[str, Any] = {"error": self.message}
        if self.field is not None:
            out["field"] = self.field
        return out


def bad_request(message: str) -> Refusal:
    return Refusal(400, message)


def not_found(message: str) -> Refusal:
    return Refusal(404, message)


def unprocessable(message: str, field: str) -> Refusal:
    return Refusal(422, message, field)
