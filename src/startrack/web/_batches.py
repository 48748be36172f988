"""Batches: several images processed with one set of options as one result set, with its own page.

A batch is ``<data-dir>/batches/<id>/batch.json``: its name, its jobs (one solve job per image),
where the images came from (uploaded files, or a folder under ``--root``) and when. The jobs are
ordinary jobs; the batch only groups them, so an analysis can take it as a result set.

Folder mode (:func:`folder_images`): the folder is given relative to ``--root``; the joined path
is resolved (symlinks followed) and must stay inside the resolved root, else the folder does not
exist as far as the client can tell (404). Its image files (by suffix, not recursive, sorted) are
copied into the jobs' folders; a file that is a symlink resolving outside the root is skipped and
listed as such.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._jobs import JOB_ID, check_id, new_id, now_iso, read_json, write_json
from ._refusals import Refusal

MAX_NAME = 80


class BatchStore:
    """The batches under one folder."""

    def __init__(self, batches_dir: Path):
        self.root = Path(batches_dir)
        self.root.mkdir(parents=True, exist_ok=True)

    def create(self, name: str, job_ids: list[str], source: dict[str, Any], batch_id: str | None = None) -> str:
        """A new batch of ``job_ids``; ``batch_id`` may be one :func:`~.jobs.new_id` made earlier."""
        batch_id = check_id(batch_id or new_id(), "batch")
        folder = self.root / batch_id
        folder.mkdir()
        write_json(folder / "batch.json", {"id": batch_id, "name": clean_name(name) or f"batch {batch_id[:8]}",
                                           "created": now_iso(), "jobs": job_ids, "source": source})
        return batch_id

    def get(self, batch_id: str) -> dict[str, Any]:
        path = self.root / check_id(batch_id, "batch") / "batch.json"
        if not path.is_file():
            raise Refusal(404, f"no batch {batch_id!r}")
        return read_json(path)

    def ids(self) -> list[str]:
        found = [(read_json(p / "batch.json")["created"], p.name) for p in self.root.iterdir()
                 if JOB_ID.match(p.name) and (p / "batch.json").is_file()]
        return [batch_id for _, batch_id in sorted(found)]


def clean_name(name: str | None) -> str:
    """A display name: printable characters only, at most :data:`MAX_NAME`."""
    return "".join(c for c in (name or "") if c.isprintable())[:MAX_NAME].strip()


def folder_images(root: Path | None, relative: str) -> tuple[Path, list[Path], list[str]]:
    """The folder ``relative`` under ``root``, its image files and the names skipped (module docstring)."""
    if root is None:
        raise Refusal(404, "folder mode is off: start the server with --root DIR to process folders under DIR")
    from ..io import IMAGE_SUFFIXES, in_name_order

    if not isinstance(relative, str) or "\x00" in relative:
        raise Refusal(422, "folder must be a path relative to --root", "folder")
    folder = (root / relative.lstrip("/")).resolve()
    if not folder.is_relative_to(root) or not folder.is_dir():
        raise Refusal(404, f"no folder {relative!r} under --root")
    images, skipped = [], []
    for path in in_name_order(list(folder.iterdir())):
        if path.suffix.lower() not in IMAGE_SUFFIXES or not path.is_file():
            continue
        if not path.resolve().is_relative_to(root):
            skipped.append(f"{path.name}: a link out of --root")
            continue
        images.append(path)
    if not images:
        raise Refusal(404, f"folder {relative!r} holds no image files ({', '.join(sorted(IMAGE_SUFFIXES))})")
    return folder, images, skipped


def list_folders(root: Path | None, limit: int = 200) -> list[str]:
    """Sub-folders of ``root`` (relative, sorted; two levels) that hold image files, for the upload page."""
    from ..io import IMAGE_SUFFIXES

    if root is None:
        return []
    out = []
    for folder in sorted([root, *root.glob("*"), *root.glob("*/*")]):
        if folder.is_dir() and folder.resolve().is_relative_to(root) and any(
                p.suffix.lower() in IMAGE_SUFFIXES for p in folder.iterdir()):
            out.append(str(folder.relative_to(root)) if folder != root else ".")
        if len(out) >= limit:
            break
    return out
