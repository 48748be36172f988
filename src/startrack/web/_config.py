"""The server's settings, checked once: where the data lives, how many workers, the limits."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..cache import cache_dir
from ..errors import InvalidInputError

DEFAULT_PORT = 8000
DEFAULT_MAX_UPLOAD_MB = 64.0
DEFAULT_TIME_LIMIT_S = 120.0
DEFAULT_MAX_QUEUED = 32
DEFAULT_MAX_PIXELS = 100_000_000
"""Largest image accepted (pixels), checked from the file's header before any decoding."""
MAX_SIDE_PX = 40_000
"""Largest width or height accepted, pixels."""
MIN_SIDE_PX = 16
"""Smallest width or height accepted, pixels."""


def default_data_dir() -> Path:
    """``<user cache>/web``, the default ``--data-dir`` (the cache of :mod:`startrack.cache`)."""
    return cache_dir() / "web"


@dataclass(frozen=True)
class WebConfig:
    """Settings of one server.

    Attributes
    ----------
    data_dir : Path
        Jobs and batches are kept under it (``jobs/<id>/``, ``batches/<id>/``); created if missing.
    workers : int
        Worker processes (1 to 16).
    max_upload_mb : float
        Largest request body, MB (10^6 bytes); larger ones are refused with 413 while they stream.
    root : Path or None
        Folder whose sub-folders may be processed as batches (folder mode); None disables it.
    time_limit_s : float
        Wall-clock limit of one job in its worker; a job over it is killed and ends as failed.
    max_queued : int
        Jobs that may wait for a worker; one more is refused with 429.
    max_pixels : int
        Largest image (width x height) accepted, checked from the header.
    prewarm : bool
        Workers load the catalog and the default pattern database when they start.
    """

    data_dir: Path = field(default_factory=default_data_dir)
    workers: int = 1
    max_upload_mb: float = DEFAULT_MAX_UPLOAD_MB
    root: Path | None = None
    time_limit_s: float = DEFAULT_TIME_LIMIT_S
    max_queued: int = DEFAULT_MAX_QUEUED
    max_pixels: int = DEFAULT_MAX_PIXELS
    prewarm: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "data_dir", Path(self.data_dir).expanduser())
        _check_int("workers", self.workers, 1, 16)
        _check_int("max_queued", self.max_queued, 1, 10_000)
        _check_int("max_pixels", self.max_pixels, MIN_SIDE_PX**2, 10**10)
        for name, value in (("max_upload_mb", self.max_upload_mb), ("time_limit_s", self.time_limit_s)):
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be a positive number, got {value!r}")
        if self.root is not None:
            root = Path(self.root).expanduser()
            if not root.is_dir():
                raise InvalidInputError(f"root {root} is not a folder; give an existing folder of images")
            object.__setattr__(self, "root", root.resolve())

    @property
    def max_upload_bytes(self) -> int:
        """``max_upload_mb`` in bytes."""
        return int(self.max_upload_mb * 1e6)

    @property
    def jobs_dir(self) -> Path:
        return self.data_dir / "jobs"

    @property
    def batches_dir(self) -> Path:
        return self.data_dir / "batches"

    @property
    def cameras_dir(self) -> Path:
        """Camera profiles (``<name>.json``, the fields of :class:`startrack.camera.Camera`)."""
        return self.data_dir / "cameras"


def _check_int(name: str, value, low: int, high: int) -> None:
    if not (isinstance(value, int) and not isinstance(value, bool) and low <= value <= high):
        raise InvalidInputError(f"{name} must be a whole number within {low}..{high}, got {value!r}")
