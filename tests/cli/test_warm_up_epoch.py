"""The warm-up of ``startrack solve IMAGE`` solves its catalog stars at the epoch the image's solve
will take, so the solver's catalog stars of that epoch are prepared once, outside the solve time."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits
from astropy.time import Time

import startrack.cli._solve_cmd as solve_cmd
from startrack.cli._batch_warmup import warm_up
from startrack.cli._progress import ensure_database_for
from startrack.errors import InvalidInputError
from startrack.solve import solve_stars


def test_the_warm_up_star_list_solves_at_the_given_epoch(monkeypatch):
    solved = []
    monkeypatch.setattr("startrack.solve.solve_stars", lambda *a, **k: solved.append(solve_stars(*a, **k)))
    ensure_database_for(fov_range_deg=(5.0, 35.0))
    warm_up(fov_range_deg=(5.0, 35.0), epoch=2024.5)
    assert len(solved) == 1 and solved[0].solved
    assert solved[0].epoch_jyear == 2024.5 and solved[0].epoch_source == "given"


def _fits(path, date_obs: str):
    noise = np.random.default_rng(3).normal(100.0, 5.0, (64, 80)).astype(np.float32)
    fits.PrimaryHDU(noise, header=fits.Header([("DATE-OBS", date_obs)])).writeto(path)
    return path


@pytest.fixture
def warm_ups(monkeypatch) -> list[dict]:
    calls: list[dict] = []
    monkeypatch.setattr(solve_cmd, "warm_up", lambda **options: calls.append(options))
    return calls


def test_solve_warms_up_at_the_epoch_of_the_image_header(tmp_path, warm_ups, capsys):
    image = _fits(tmp_path / "dated.fits", "2024-06-01T12:00:00")
    assert solve_cmd.main([str(image), "--fov-deg", "10", "--json"]) == 1  # noise: not solved
    (options,) = warm_ups
    expected = Time("2024-06-01T12:00:00", scale="utc").tdb.jyear
    assert options["epoch"] == pytest.approx(expected, abs=1e-9)  # Julian years
    assert options["fov_deg"] == 10.0


def test_a_given_epoch_wins_and_an_unreadable_date_is_left_to_the_solve(tmp_path, warm_ups):
    dated = _fits(tmp_path / "dated.fits", "2024-06-01T12:00:00")
    assert solve_cmd.main([str(dated), "--fov-deg", "10", "--epoch", "2010.0", "--json"]) == 1
    assert warm_ups[-1]["epoch"] == 2010.0
    bad = _fits(tmp_path / "bad.fits", "yesterday")
    with pytest.raises(InvalidInputError, match="bad.fits: .*DATE-OBS"):  # the solve names the file
        solve_cmd.main([str(bad), "--fov-deg", "10"])
    assert warm_ups[-1]["epoch"] is None


def test_the_solving_commands_skip_the_collections_of_interpreter_shutdown():
    """0.3-0.4 s of ``startrack solve IMAGE`` went to the final garbage collections."""
    import subprocess
    import sys

    code = ("import atexit, gc, sys\n"
            "atexit.register(lambda: print('frozen at exit:', gc.get_freeze_count() > 0))\n"  # runs after the hook
            "from startrack.cli._process_gc import no_collection_at_exit\n"
            "no_collection_at_exit(); no_collection_at_exit()\n"
            "print('frozen before:', gc.get_freeze_count() > 0)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert done.stdout.splitlines() == ["frozen before: False", "frozen at exit: True"]
