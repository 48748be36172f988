"""The campaign level "rig": heads swept, the joint and head 0's own errors in the same rows."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._run import run_campaign
from startrack.analysis.campaign.levels import get_level

SPEC = """
[campaign]
name = "rig-heads"
level = "rig"
trials = 12
seed = 1
[sweep]
heads = [1, 2]
"""


def test_rig_level_sweeps_heads_and_compares_with_one_head(tmp_path):
    table = run_campaign(SPEC, tmp_path / "out", sync=True, report=False).to_pydict()
    heads = np.array(table["heads"])
    roll = np.abs(np.array(table["err_roll_arcsec"]))
    single = np.abs(np.array(table["single_err_roll_arcsec"]))
    assert all(table["correct"]) and set(table["mode"]) == {"single-head"}
    np.testing.assert_allclose(roll[heads == 1], single[heads == 1], atol=1e-6)  # one head: the same solution
    assert np.sqrt(np.mean(roll[heads == 2] ** 2)) < 0.3 * np.sqrt(np.mean(single[heads == 2] ** 2))
    assert list(np.array(table["heads_used"])[heads == 2]) == [2] * 12


def test_coinciding_heads_are_refused():
    level = get_level("rig")
    params = {name: p.default for name, p in level.params.items()}
    level.check(params)
    with pytest.raises(SpecError, match="separation_deg"):
        level.check({**params, "separation_deg": 0.0})
