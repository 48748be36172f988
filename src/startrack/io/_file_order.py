"""The order of a folder's images: by name, with the numbers in names compared as numbers
(``frame_2`` before ``frame_10``), as cameras and people number frames without padding."""

from __future__ import annotations

import re
from pathlib import Path

_DIGITS = re.compile(r"(\d+)")


def natural_key(path: Path) -> tuple[list[int | str], str]:
    """Sort key of ``path``'s name: its runs of digits as integers, the text between them in lower
    case (``re.split`` alternates text and digits, so two keys compare like with like), then the
    name itself to keep the order total."""
    parts = _DIGITS.split(path.name)
    return [int(part) if k % 2 else part.lower() for k, part in enumerate(parts)], path.name


def in_name_order(paths: list[Path]) -> list[Path]:
    """``paths`` sorted by :func:`natural_key`."""
    return sorted(paths, key=natural_key)
