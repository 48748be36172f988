"""The campaign's output folder: ``manifest.json``, ``trials/`` Parquet parts, resuming.

Each finished chunk is written at once as ``trials/part-CCCCC-KKKKKK.parquet`` (cell C, first
trial K) through a temporary file and a rename, so an interrupted run leaves only whole parts,
and ``pyarrow.parquet.read_table(OUT / "trials")`` reads them all as one table (it skips the
dot-named temporary files). ``--resume`` runs only the chunks whose part is missing, with the
chunk size recorded in the manifest, and refuses a folder that holds another campaign, or one whose
manifest or parts are damaged (:mod:`._folder`), before any trial runs.
"""

from __future__ import annotations

import contextlib
import json
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from ...errors import InvalidInputError
from ...io import atomic_path
from ._folder import load_manifest, part_key, part_paths, read_parts
from ._spec import CampaignSpec
from ._trials import Chunk


def utc_now() -> str:
    """The current time as ISO 8601 UTC, to the second."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def write_json(path: Path, data: Any) -> None:
    """Write JSON atomically (indented, UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")


@dataclass(frozen=True)
class CampaignStore:
    """The files of one campaign output folder."""

    out: Path
    made_out: bool = False
    """Whether this run made ``out`` (then :meth:`discard` removes it too)."""

    @property
    def manifest_path(self) -> Path:
        return self.out / "manifest.json"

    @property
    def trials_dir(self) -> Path:
        return self.out / "trials"

    def part_path(self, key: tuple[int, int]) -> Path:
        return self.trials_dir / f"part-{key[0]:05d}-{key[1]:06d}.parquet"

    def done_keys(self) -> set[tuple[int, int]]:
        """(cell, first trial) of every chunk whose part is on disk."""
        return {part_key(path) for path in part_paths(self.trials_dir)}

    def write_part(self, chunk: Chunk, table: pa.Table) -> Path:
        path = self.part_path(chunk.key)
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)
        return path

    def read_manifest(self) -> dict[str, Any]:
        """The checked manifest (:func:`._folder.load_manifest`: an InvalidInputError if damaged)."""
        return load_manifest(self.out)

    def write_manifest(self, manifest: dict[str, Any]) -> None:
        write_json(self.manifest_path, manifest)

    def discard(self) -> None:
        """Remove the manifest and the (empty) trials folder of a run that never finished a chunk,
        and ``out`` itself when this run made it and it is empty (a refused scheduler left it)."""
        self.manifest_path.unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            self.trials_dir.rmdir()
            if self.made_out:
                self.out.rmdir()

    def read_trials(self) -> pa.Table:
        """Every trial row on disk, sorted by cell and trial (:func:`._folder.read_parts`: an
        InvalidInputError if there is none or a part is damaged)."""
        return read_parts(self.out)


def open_store(out: str | Path, spec: CampaignSpec, *, resume: bool) -> tuple[CampaignStore, dict | None]:
    """The store for a run into ``out``, and the manifest to resume (None for a fresh run).

    Raises
    ------
    InvalidInputError
        If ``out`` already holds a campaign and ``resume`` is false, if it holds another spec's
        campaign or a damaged one (its manifest, a part), or if it is a file.
    """
    store = CampaignStore(Path(out), made_out=not Path(out).exists())
    if store.out.exists() and not store.out.is_dir():
        raise InvalidInputError(f"--out {store.out} is a file; give a folder")
    started = store.manifest_path.exists() or bool(part_paths(store.trials_dir))
    if not started:
        store.trials_dir.mkdir(parents=True, exist_ok=True)
        return store, None
    if not resume:
        raise InvalidInputError(f"{store.out} already holds a campaign; pass --resume to finish it, "
                                "or choose another --out")
    manifest = store.read_manifest()
    if manifest["spec"] != spec.as_dict():
        raise InvalidInputError(f"{store.out} holds the campaign {manifest['name']!r} of another spec; "
                                "--resume needs the same spec (or choose another --out)")
    if part_paths(store.trials_dir):
        store.read_trials()  # refuses a damaged part before any trial runs
    store.trials_dir.mkdir(exist_ok=True)
    return store, manifest
