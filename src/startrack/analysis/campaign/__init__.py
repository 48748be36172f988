"""Monte Carlo campaigns: a TOML spec, trials on Dask, Parquet storage, reports and error budgets.

>>> from startrack.analysis.campaign import run_campaign, load_spec      # doctest: +SKIP
>>> trials = run_campaign(load_spec("fov-noise.toml"), "out/fov-noise")  # doctest: +SKIP

See ``docs/campaigns.md``. Needs the ``campaign`` extra (Dask distributed and pyarrow).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ... import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._aggregate import as_columns, cell_table, read_campaign
    from ._budget_report import budget_text
    from ._budget_terms import contribution, ecss_terms, variance_components
    from ._engine import dask_client, run_dask
    from ._params import SpecError, param_table
    from ._reference import check_references, reference_tables, reference_text
    from ._report import register_section, write_report
    from ._rerun import Rerun, rerun_trial, rows_agree
    from ._run import default_chunk_size, run_campaign
    from ._shipped import find_spec, list_specs
    from ._spec import CampaignSpec, Cell, load_spec, parse_spec
    from ._stats import percentiles, rms
    from ._store import CampaignStore
    from ._summary import summary_text
    from ._trials import plan_chunks

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
