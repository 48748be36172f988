"""A campaign level for the tests: a stars trial that raises, or kills its process, when the
first number it draws after the attitude is below ``fail_fraction``.

It is registered from outside the package (as a user's level would be); the spec carries it, so
Dask workers import this module when they unpickle the spec. The warm-up trial draws 0.637 from
``default_rng(0)``, so it never fails for ``fail_fraction`` below that.
"""

from __future__ import annotations

import os

from startrack.analysis.campaign._params import Param, params_by_name
from startrack.analysis.campaign.levels import Level, register
from startrack.analysis.campaign.levels import _stars as stars

FAULT_PARAMS = (
    Param("fail_fraction", "float", 0.0, "share of trials that fail", lo=0.0, hi=1.0),
    Param("fault", "str", "raise", "how a trial fails", choices=("raise", "exit", "interrupt")),
)


def run(params, rot, rng, tolerance_px):
    if rng.random() < params["fail_fraction"]:
        if params["fault"] == "exit":
            os._exit(3)
        if params["fault"] == "interrupt":  # what Ctrl-C inside a compiled function comes back as
            raise SystemError("CPUDispatcher(<function search>) returned a result with an exception set") \
                from KeyboardInterrupt()
        raise RuntimeError("faulty level: this trial fails on purpose")
    return stars.run(params, rot, rng, tolerance_px)


LEVEL = register(Level(name="test-faulty", doc="stars trials that fail on purpose",
                       params=params_by_name(tuple(stars.PARAMS.values()), FAULT_PARAMS), run=run,
                       columns=stars.LEVEL.columns, chunk_trials=5))
