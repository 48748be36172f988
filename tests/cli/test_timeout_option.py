"""--timeout-s: the lost-in-space search's time limit from the command line (the matcher's
timeout_s; 5 s by default), for slow or busy machines."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_cli import run as _run


def test_the_time_limit_given_is_the_searchs(tmp_path):
    rng = np.random.default_rng(0)
    points = tmp_path / "random.csv"
    points.write_text("x,y\n" + "".join(f"{x:.2f},{y:.2f}\n" for x, y in rng.uniform(0, 1023, (40, 2))))
    code, out, _ = _run("solve-stars", points, "--width", 1024, "--height", 1024, "--timeout-s", 1e-9, "--json")
    assert code == 1 and json.loads(out)["status"] == "timeout"  # random points: the default searches to no_match


@pytest.mark.parametrize("value", ["0", "-3", "nan", "inf"])
def test_a_time_limit_that_is_not_a_positive_number_is_refused(tmp_path, value):
    stars = tmp_path / "stars.csv"
    stars.write_text("x,y\n1,2\n3,4\n5,6\n7,8\n")
    code, out, err = _run("solve-stars", stars, "--width", 100, "--height", 100, "--timeout-s", value)
    assert code == 2 and out == "" and "error: --timeout-s must be a" in err, err
