"""The Dask worker plugin that warms each worker for a campaign (imports ``distributed``)."""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from .engine import warm_cells
from .spec import CampaignSpec


class WarmUp(WorkerPlugin):
    """Run one throwaway trial of every cell when a worker starts or joins (see :mod:`.engine`)."""

    def __init__(self, spec: CampaignSpec):
        self.spec = spec

    def setup(self, worker: Any) -> None:
        warm_cells(self.spec)
