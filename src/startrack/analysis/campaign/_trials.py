"""Running trials: each from its own random stream, a raising trial becoming a failure row.

Trial ``k`` of cell ``c`` draws everything (attitude first, then the level's noise) from
``numpy.random.default_rng(SeedSequence(seed, spawn_key=(c, k)))``, so a trial's row does not
depend on the number of workers, the chunking, or the trials run before it in the same process.
A chunk (consecutive trials of one cell) is the unit of work sent to a worker; its rows come back
as one Arrow table of :func:`trial_schema`.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from ...errors import hidden_interruption
from ._attitudes import trial_attitude
from ._outcome import COLUMNS, arrow_type, as_column_value, empty_value, failure_columns
from ._spec import CampaignSpec, Cell
from .levels import TrialOutput


@dataclass(frozen=True)
class Chunk:
    """Trials ``start`` to ``stop - 1`` of one cell."""

    cell: Cell
    start: int
    stop: int

    @property
    def size(self) -> int:
        return self.stop - self.start

    @property
    def key(self) -> tuple[int, int]:
        return (self.cell.index, self.start)


def plan_chunks(cells: list[Cell], trials: int, chunk_size: int) -> list[Chunk]:
    """The chunks of a campaign, cell by cell, ``chunk_size`` trials each (the last may be shorter)."""
    return [Chunk(cell, start, min(start + chunk_size, trials)) for cell in cells
            for start in range(0, trials, chunk_size)]


def trial_rng(seed: int, cell: int, trial: int) -> np.random.Generator:
    """The random stream of trial ``trial`` of cell ``cell``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(cell, trial)))


def trial_schema(spec: CampaignSpec) -> pa.Schema:
    """Columns of the trial table: cell, trial, the swept parameters (and ``source`` in budget
    mode), the common columns, ``wall_s`` (the whole trial, simulation included), then the level's."""
    level = spec.level_def
    fields = [pa.field("cell", pa.int32()), pa.field("trial", pa.int32())]
    fields += [pa.field(name, arrow_type(level.params[name].kind)) for name in spec.swept]
    if spec.mode == "budget":
        fields.append(pa.field("source", pa.string()))
    fields += [pa.field(name, kind) for name, kind in COLUMNS.items() if name not in ("cell", "trial")]
    fields.append(pa.field("wall_s", pa.float64()))
    fields += [pa.field(name, kind) for name, kind in level.columns.items()]
    return pa.schema(fields)


def _keys(spec: CampaignSpec, cell: Cell, k: int) -> dict[str, Any]:
    keys: dict[str, Any] = {"cell": cell.index, "trial": k}
    keys.update({name: as_column_value(cell.params[name]) for name in spec.swept})
    if spec.mode == "budget":
        keys["source"] = cell.source or ""
    return keys


def failure_row(spec: CampaignSpec, cell: Cell, k: int, status: str, error: str, rot=None) -> dict[str, Any]:
    """The row of a trial that raised (``ERROR``) or whose worker died (``LOST``)."""
    row = {**_keys(spec, cell, k), **failure_columns(status, error, rot), "wall_s": float("nan")}
    row.update({name: empty_value(kind) for name, kind in spec.level_def.columns.items()})
    return row


def run_trial(spec: CampaignSpec, cell: Cell, k: int) -> TrialOutput:
    """Trial ``k`` of ``cell``: its row, and its image where the level renders one."""
    rng = trial_rng(spec.seed, cell.index, k)
    rot = None
    t0 = time.perf_counter()
    try:
        rot = trial_attitude(spec.attitudes, k, spec.trials, rng)
        out = spec.level_def.run(cell.params, rot, rng, spec.tolerance_px)
    except Exception as exc:  # a trial that raises is a result: a failure row with its traceback
        interruption = hidden_interruption(exc)  # ... unless a signal stopped it inside compiled code
        if interruption is not None:
            raise interruption from None
        return TrialOutput(failure_row(spec, cell, k, "ERROR", traceback.format_exc(), rot))
    row = {**_keys(spec, cell, k), **out.row, "wall_s": time.perf_counter() - t0}
    return TrialOutput(row, out.image, out.truth)


def rows_table(spec: CampaignSpec, rows: list[dict[str, Any]]) -> pa.Table:
    """Rows as an Arrow table of :func:`trial_schema`."""
    schema = trial_schema(spec)
    return pa.Table.from_pylist([{name: row.get(name) for name in schema.names} for row in rows], schema=schema)


def run_chunk(spec: CampaignSpec, chunk: Chunk) -> pa.Table:
    """Every trial of ``chunk``, as one table (what a worker returns)."""
    return rows_table(spec, [run_trial(spec, chunk.cell, k).row for k in range(chunk.start, chunk.stop)])


def lost_table(spec: CampaignSpec, chunk: Chunk, error: str) -> pa.Table:
    """Failure rows (``LOST``) for a chunk whose worker died; the attitude is recomputed (cheap)."""
    rows = []
    for k in range(chunk.start, chunk.stop):
        rot = trial_attitude(spec.attitudes, k, spec.trials, trial_rng(spec.seed, chunk.cell.index, k))
        rows.append(failure_row(spec, chunk.cell, k, "LOST", error, rot))
    return rows_table(spec, rows)
