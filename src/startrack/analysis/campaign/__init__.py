"""Monte Carlo campaigns: a TOML spec, trials on Dask, Parquet storage, reports and error budgets.

See ``docs/campaigns.md``.
"""
