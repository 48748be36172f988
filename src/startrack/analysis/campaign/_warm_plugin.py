"""The Dask worker plugin that prepares each worker for a campaign (imports ``distributed``)."""

from __future__ import annotations

import ctypes
import os
import sys
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from ._engine import warm_cells
from ._spec import CampaignSpec

M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
"""glibc ``mallopt`` parameters (malloc.h)."""
ARRAY_HEAP_BYTES = 64 * 2**20
"""Arrays up to this size come from the heap (not fresh zeroed mappings) once the plugin ran."""


def undo_malloc_trim() -> bool:
    """Undo the ``MALLOC_TRIM_THRESHOLD_`` a Dask nanny sets in its worker's environment.

    That variable fixes glibc's mmap threshold at 128 KiB, so every image-sized array is mapped,
    zeroed and unmapped afresh, which slows image-level trials (docs/campaigns.md gives the figure). On glibc,
    with the variable set, raise both thresholds to :data:`ARRAY_HEAP_BYTES`; elsewhere do
    nothing. Returns whether it changed anything.
    """
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ or not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return False
    return bool(libc.mallopt(M_MMAP_THRESHOLD, ARRAY_HEAP_BYTES)) and bool(
        libc.mallopt(M_TRIM_THRESHOLD, 2 * ARRAY_HEAP_BYTES))


class WarmUp(WorkerPlugin):
    """When a worker starts or joins: undo the nanny's malloc setting, then run one throwaway
    trial of every cell (see :mod:`._engine`)."""

    def __init__(self, spec: CampaignSpec):
        self.spec = spec

    def setup(self, worker: Any) -> None:
        undo_malloc_trim()
        warm_cells(self.spec)
