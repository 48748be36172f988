"""The benchmark's method runs: chunks a method solved in turns join back in list order."""

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from methods import MethodRun, concatenate_runs  # noqa: E402


def test_chunks_join_in_order_with_per_list_extras_joined_and_the_rest_kept():
    rot = Rotation.from_rotvec([0.1, 0.0, 0.0])
    first = MethodRun("cedar-solve", np.array([True, False]), [rot, None], np.array([1e-3, 2e-3]),
                      {"ra_deg": np.array([10.0, np.nan]), "database": {"patterns": 7}})
    second = MethodRun("cedar-solve", np.array([True]), [rot], np.array([3e-3]),
                       {"ra_deg": np.array([30.0]), "database": {"patterns": 7}})
    joined = concatenate_runs([first, second])
    assert joined.method == "cedar-solve"
    assert joined.solved.tolist() == [True, False, True]
    assert joined.estimates == [rot, None, rot]
    assert np.array_equal(joined.time_s, [1e-3, 2e-3, 3e-3])
    assert np.array_equal(joined.extra["ra_deg"], [10.0, np.nan, 30.0], equal_nan=True)
    assert joined.extra["database"] == {"patterns": 7}
