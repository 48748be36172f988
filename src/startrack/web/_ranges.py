"""Range requests on a job's files (RFC 9110, section 14): the header Starlette is handed.

Starlette's ``FileResponse`` serves byte ranges itself (206, and ``multipart/byteranges`` for
several), but it answers a range unit it does not know with a plain-text 400, where RFC 9110
section 14.2 says a server MUST ignore the header; a malformed or backwards range with a 400 too;
a set in which one range starts past the end with a 416, though the others could be served; and
its 416 has an empty plain-text body. So the header is settled here first:

- not a valid ``bytes=`` range set (another unit, a malformed or backwards range), or an
  ``If-Range`` that names another version of the file: the header is dropped and the whole file
  is served (200), as the RFC allows;
- valid, and no range overlaps the file: a JSON refusal, 416, with ``Content-Range: bytes */SIZE``;
- valid: the header is rewritten to the satisfiable ranges alone, which Starlette serves.
"""

from __future__ import annotations

import re
from collections.abc import MutableMapping
from typing import Any

from ._refusals import Refusal

_RANGE = re.compile(r"^(\d*)-(\d*)$")


def byte_ranges(value: str, size: int) -> list[tuple[int, int]] | None:
    """The satisfiable ranges of a ``Range`` header's value over a file of ``size`` bytes.

    Parameters
    ----------
    value : str
        The header's value, e.g. ``"bytes=0-99, -20"``.
    size : int
        The file's length, bytes.

    Returns
    -------
    list of (int, int) or None
        ``(first, last)`` byte offsets, inclusive, clipped to the file, in the order asked (empty
        when none overlaps the file); None when ``value`` is not a valid byte-range set.
    """
    unit, equals, spec = value.partition("=")
    parts = [p.replace(" ", "").replace("\t", "") for p in spec.split(",")]
    parts = [p for p in parts if p]  # RFC 9110 section 5.6.1: empty list elements are allowed
    if unit.strip().lower() != "bytes" or not equals or not parts:
        return None
    out = []
    for part in parts:
        match = _RANGE.match(part)
        if match is None or match.group(0) == "-":
            return None
        first, last = match.groups()
        if not first:  # a suffix: the last N bytes
            if int(last) > 0 and size > 0:
                out.append((max(size - int(last), 0), size - 1))
        elif last and int(last) < int(first):
            return None
        elif int(first) < size:
            out.append((int(first), min(int(last), size - 1) if last else size - 1))
    return out


def settle_range(scope: MutableMapping[str, Any], size: int, validators: tuple[str, ...], name: str) -> None:
    """Drop, refuse or rewrite the request's ``Range`` header (module docstring), in ``scope``.

    Parameters
    ----------
    scope : dict
        The ASGI scope of the request; its ``headers`` are replaced when the header changes.
    size : int
        The file's length, bytes.
    validators : tuple of str
        The file's ``ETag`` and ``Last-Modified`` values, which a matching ``If-Range`` names.
    name : str
        The file's name, for the refusal's message.

    Raises
    ------
    Refusal
        416 when the ranges are valid and none overlaps the file.
    """
    headers = scope.get("headers", [])
    values = [v.decode("latin-1") for k, v in headers if k.lower() == b"range"]
    if not values:
        return
    if_range = [v.decode("latin-1") for k, v in headers if k.lower() == b"if-range"]
    ranges = byte_ranges(values[0], size) if len(values) == 1 else None
    if if_range and (if_range[0].startswith("W/") or if_range[0] not in validators):
        ranges = None
    if ranges == []:
        valid = f"valid byte offsets are 0 to {size - 1}" if size else "it is empty"
        raise Refusal(416, f"Range {values[0]!r}: no byte of it lies in {name}, which is {size} bytes long "
                           f"({valid})", "Range", headers={"Content-Range": f"bytes */{size}"})
    kept = [(k, v) for k, v in headers if k.lower() not in (b"range", b"if-range")]
    if ranges is not None:
        kept.append((b"range", ("bytes=" + ",".join(f"{a}-{b}" for a, b in ranges)).encode("latin-1")))
    scope["headers"] = kept
