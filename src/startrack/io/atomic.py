"""Atomic file writing: write a temporary file beside the target, then rename it over.

A reader never sees a half-written file, and an error while writing leaves no file behind
(the target keeps its previous content if it existed). DESIGN.md §3 (Data).
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import InvalidInputError


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it to ``path`` on success.

    The temporary file is named ``.<name>.<random>.tmp`` and is removed if the body raises.
    It is created with ordinary permissions (the process umask applies), not mkstemp's 0600.

    Raises
    ------
    InvalidInputError
        If the target's folder does not exist or the target is a folder.
    """
    target = Path(path)
    if not target.parent.is_dir():
        raise InvalidInputError(f"cannot write {target}: folder {target.parent} does not exist")
    if target.is_dir():
        raise InvalidInputError(f"cannot write {target}: it is a folder, give a file name")
    tmp = target.with_name(f".{target.name}.{uuid.uuid4().hex}.tmp")
    try:
        yield tmp
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)
