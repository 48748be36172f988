"""Reproduce one trial of a finished campaign exactly: ``startrack campaign rerun OUT --cell C --trial K``.

The spec is read back from the manifest and the trial re-run in this process from its own random
stream, so its image is the same bit for bit and its row the same but for the times (when the
code and the catalog are those the manifest records). With ``save_dir`` the trial's frame is
written: the image with its truth (FITS) at the image level, the star list (CSV) at the stars level.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import InvalidInputError
from ...io import atomic_path
from ._folder import part_paths
from ._spec import parse_spec
from ._store import CampaignStore
from ._trials import run_trial
from .levels import TrialOutput

TIME_COLUMNS = ("time_s", "wall_s")


@dataclass(frozen=True)
class Rerun:
    """A re-run trial: its fresh row, the stored row (None if that chunk never finished),
    whether they agree (times aside) and the files written."""

    row: dict[str, Any]
    stored: dict[str, Any] | None
    same: bool | None
    files: tuple[Path, ...] = ()


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def rows_agree(fresh: dict[str, Any], stored: dict[str, Any]) -> bool:
    """Every column but the times (:data:`TIME_COLUMNS`, ``time_*_s``) equal (NaN equals NaN)."""
    keys = [k for k in stored if k not in TIME_COLUMNS and not (k.startswith("time_") and k.endswith("_s"))]
    return all(_same(fresh.get(k), stored[k]) for k in keys)


def _stored_row(store: CampaignStore, cell: int, trial: int) -> dict[str, Any] | None:
    if not part_paths(store.trials_dir):
        return None
    import pyarrow.compute as pc

    table = store.read_trials()
    hit = table.filter(pc.and_(pc.equal(table["cell"], cell), pc.equal(table["trial"], trial)))
    return hit.to_pylist()[0] if hit.num_rows else None


def _save(out: TrialOutput, folder: Path, stem: str) -> tuple[Path, ...]:
    folder.mkdir(parents=True, exist_ok=True)
    if out.image is not None:
        from ...io import write_frame

        return tuple(write_frame(folder / f"{stem}.fits", out.image, out.truth))
    stars = out.truth
    if stars is None or not hasattr(stars, "is_real"):
        return ()
    path = folder / f"{stem}.csv"
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["x", "y", "flux", "is_real", "hip"])
        for row in zip(stars.x, stars.y, stars.flux, stars.is_real, stars.hip, strict=True):
            writer.writerow([f"{row[0]:.6f}", f"{row[1]:.6f}", f"{row[2]:.6g}", int(row[3]), int(row[4])])
    return (path,)


def rerun_trial(out: str | Path, cell: int, trial: int, *, save_dir: str | Path | None = None) -> Rerun:
    """Re-run trial ``trial`` of cell ``cell`` of the campaign in folder ``out``.

    Raises
    ------
    InvalidInputError
        If ``out`` is not a campaign folder or a damaged one (its manifest, a trial part: checked
        before the trial runs), or the cell or trial is out of range.
    """
    store = CampaignStore(Path(out))
    manifest = store.read_manifest()
    spec = parse_spec(manifest["spec_text"], str(store.manifest_path))
    cells = spec.cells()
    if not 0 <= cell < len(cells):
        raise InvalidInputError(f"--cell must be in 0..{len(cells) - 1} for this campaign, got {cell}")
    if not 0 <= trial < spec.trials:
        raise InvalidInputError(f"--trial must be in 0..{spec.trials - 1} for this campaign, got {trial}")
    stored = _stored_row(store, cell, trial)
    fresh = run_trial(spec, cells[cell], trial)
    files = _save(fresh, Path(save_dir), f"cell{cell}-trial{trial}") if save_dir is not None else ()
    same = None if stored is None else rows_agree(fresh.row, stored)
    return Rerun(fresh.row, stored, same, files)
