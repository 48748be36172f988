"""The warm-up before the first solve: numba compiling is announced once on stderr, and the
warm-up star list (catalog stars through a camera of the command's field of view) solves."""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.core import event

from startrack.cli._batch_warmup import _CompileNotice
from startrack.cli._progress import ensure_database_for
from startrack.solve import solve_stars
from startrack.warm_up import warm_up_fov_deg


def test_compiling_is_announced_once(capsys):
    notice = _CompileNotice()

    @njit  # not cached: compiled at its first call in every process
    def twice(a):
        return 2 * a

    with event.install_listener("numba:compile", notice.listener):
        twice(np.arange(3.0))
        twice(np.arange(3))  # a second signature compiles again, without a second message
    notice.finished()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2
    assert err[0].startswith("compiling startrack's solver kernels (one time after an install")
    assert err[1].startswith("compiled in ")


def test_nothing_said_without_compiling(capsys):
    notice = _CompileNotice()
    with event.install_listener("numba:compile", notice.listener):
        pass
    notice.finished()
    assert capsys.readouterr().err == ""


def test_warm_up_field_is_the_searched_one():
    assert warm_up_fov_deg(12.0, None, None) == 12.0
    assert warm_up_fov_deg(None, (5.0, 20.0), None) == 10.0  # geometric mean, deg


def test_warm_up_star_list_solves(monkeypatch):
    import startrack.cli._batch_warmup as warmup

    solved = []
    monkeypatch.setattr("startrack.solve.solve_stars", lambda *a, **k: solved.append(solve_stars(*a, **k)))
    ensure_database_for(fov_range_deg=(5.0, 35.0))
    warmup.warm_up(fov_range_deg=(5.0, 35.0))
    assert len(solved) == 1 and solved[0].solved
    assert abs(solved[0].ra_deg - 90.0) < 0.01 and abs(solved[0].dec_deg - 30.0) < 0.01  # deg


def test_warm_up_command():
    from test_cli import run

    code, out, err = run("warm-up", "--fov-range-deg", 5, 35)
    assert code == 0, err
    assert out.startswith("startrack is ready: database and compiled kernels loaded in ")
    assert run("warm-up", "--fov-range-deg", 35, 5)[0] == 2  # LO > HI is misuse


def test_warm_up_builds_the_databases_a_solve_with_no_field_searches(monkeypatch):
    """The default range and the ultra-wide one searched after it (``WIDE_RETRY_FOV_RANGE_DEG``),
    so that no first ultra-wide photo waits for its database; a range given builds that one only."""
    from test_cli import run

    import startrack.cli._batch_warmup as warmup

    built = []
    monkeypatch.setattr("startrack.cli._progress.ensure_database_for", lambda **kw: built.append(kw["fov_range_deg"]))
    monkeypatch.setattr(warmup, "warm_up", lambda **kw: None)
    assert run("warm-up")[0] == 0
    assert built == [None, (90.0, 150.0)]
    built.clear()
    assert run("warm-up", "--fov-range-deg", 5, 35)[0] == 0
    assert built == [(5.0, 35.0)]
