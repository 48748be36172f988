"""Conditional requests on a job's files (RFC 9110, section 13): when the client's copy is current.

A result file never changes once its job has finished, so a browser that shows a job's page again
asks with ``If-None-Match`` (the ``ETag`` it was given) or ``If-Modified-Since``, and should get
``304 Not Modified`` without the body. Starlette's ``FileResponse`` sends the validators but does
not answer these headers (its static files do); this module decides for the result files.
"""

from __future__ import annotations

from collections.abc import Mapping
from email.utils import parsedate_to_datetime


def not_modified(headers: Mapping[str, str], etag: str, last_modified: str) -> bool:
    """Whether a GET or HEAD of a file with these validators is answered 304.

    Parameters
    ----------
    headers : mapping of str
        The request's headers, looked up by lower-case names (Starlette's ``Headers`` ignore case).
    etag, last_modified : str
        The file's ``ETag`` and ``Last-Modified`` (an HTTP date).

    Returns
    -------
    bool
        ``If-None-Match`` lists the ETag (weak comparison) or is ``*``; without ``If-None-Match``
        (which takes precedence, RFC 9110 section 13.2.2), ``If-Modified-Since`` is a valid date
        no earlier than ``Last-Modified``. An unreadable date is ignored, as the RFC asks.
    """
    listed = headers.get("if-none-match")
    if listed is not None:
        tags = {_opaque(tag) for tag in listed.split(",")}
        return "*" in tags or _opaque(etag) in tags
    since = headers.get("if-modified-since")
    if since is None:
        return False
    try:
        return parsedate_to_datetime(last_modified) <= parsedate_to_datetime(since)
    except (TypeError, ValueError, IndexError):
        return False


def _opaque(tag: str) -> str:
    """An entity tag without its weakness prefix (the weak comparison of RFC 9110 section 8.8.3.2)."""
    tag = tag.strip()
    return tag[2:] if tag.startswith("W/") else tag
