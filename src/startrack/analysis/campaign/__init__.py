"""Monte Carlo campaigns: a TOML spec, trials on Dask, Parquet storage, reports and error budgets.

>>> from startrack.analysis.campaign import run_campaign, load_spec      # doctest: +SKIP
>>> trials = run_campaign(load_spec("fov-noise.toml"), "out/fov-noise")  # doctest: +SKIP

See ``docs/campaigns.md``. Needs the ``campaign`` extra (Dask distributed and pyarrow).
"""

from __future__ import annotations

from ... import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "as_columns": ".aggregate",
    "cell_table": ".aggregate",
    "read_campaign": ".aggregate",
    "budget_text": ".budget_report",
    "contribution": ".budget_terms",
    "ecss_terms": ".budget_terms",
    "variance_components": ".budget_terms",
    "dask_client": ".engine",
    "run_dask": ".engine",
    "SpecError": ".params",
    "param_table": ".params",
    "check_references": ".reference",
    "reference_tables": ".reference",
    "reference_text": ".reference",
    "register_section": ".report",
    "write_report": ".report",
    "Rerun": ".rerun",
    "rerun_trial": ".rerun",
    "rows_agree": ".rerun",
    "default_chunk_size": ".run",
    "run_campaign": ".run",
    "find_spec": ".shipped",
    "list_specs": ".shipped",
    "CampaignSpec": ".spec",
    "Cell": ".spec",
    "load_spec": ".spec",
    "parse_spec": ".spec",
    "percentiles": ".stats",
    "rms": ".stats",
    "CampaignStore": ".store",
    "summary_text": ".summary",
    "plan_chunks": ".trials",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
