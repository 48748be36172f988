"""Monte Carlo campaigns: a TOML spec, trials on Dask, Parquet storage, reports and error budgets.

>>> from startrack.analysis.campaign import run_campaign, load_spec      # doctest: +SKIP
>>> trials = run_campaign(load_spec("fov-noise.toml"), "out/fov-noise")  # doctest: +SKIP

See ``docs/campaigns.md``. Needs the ``campaign`` extra (Dask distributed and pyarrow).
"""

from __future__ import annotations

from .params import SpecError
from .rerun import Rerun, rerun_trial
from .run import run_campaign
from .shipped import find_spec, list_specs
from .spec import CampaignSpec, Cell, load_spec, parse_spec
from .store import CampaignStore

__all__ = [
    "CampaignSpec",
    "CampaignStore",
    "Cell",
    "Rerun",
    "SpecError",
    "find_spec",
    "list_specs",
    "load_spec",
    "parse_spec",
    "rerun_trial",
    "run_campaign",
]
