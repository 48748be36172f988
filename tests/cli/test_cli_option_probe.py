"""Every option of the quick commands given values no one should give (a negative, NaN, 1e300, a word,
an empty string): the command must end as a result (0, 1) or as bad input (2, one line), never as
"unexpected" (3) or a traceback. A probe of this kind found the values that 4f7a78a refused by name;
this keeps it from coming back as options are added. (simulate, solve and
availability here; adcs-demo, campaign, analyse and web, slower to start, were probed by hand.)"""

from __future__ import annotations

import argparse
import contextlib
import io

import numpy as np
import pytest

from startrack.cli import main
from startrack.io import write_fits

BAD_VALUES = ("-1", "nan", "1e300", "x", "")


def _parser_of(command: str, argv: list[str], monkeypatch) -> argparse.ArgumentParser:
    """The command's argument parser, caught where it parses (the commands build it inside main)."""
    caught: list[argparse.ArgumentParser] = []

    def grab(self, *args, **kwargs):
        caught.append(self)
        raise SystemExit(0)

    with monkeypatch.context() as patch:
        patch.setattr(argparse.ArgumentParser, "parse_args", grab)
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            main([command, *argv])
    return caught[0]


def _valued_options(parser: argparse.ArgumentParser) -> list[tuple[str, int]]:
    """(option string, number of values) of every option that takes values."""
    out = []
    for action in parser._actions:  # argparse keeps no public list of a parser's options
        if action.option_strings and action.nargs != 0 and action.help != argparse.SUPPRESS:
            out.append((action.option_strings[-1], action.nargs if isinstance(action.nargs, int) else 1))
    return out


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("probe")
    rng = np.random.default_rng(1)
    image = rng.poisson(100.0, (64, 64)).astype(np.uint16)
    write_fits(folder / "a.fits", image)
    write_fits(folder / "b.fits", image)
    (folder / "frames").mkdir()
    write_fits(folder / "frames" / "f0.fits", image)
    (folder / "stars.csv").write_text("x,y\n10,12\n30,40\n50,20\n20,55\n")
    return folder


COMMANDS = {
    "simulate": ["--width", "64", "--height", "64", "--seed", "1", "--out", "{d}/out/x.fits"],
    "solve-stars": ["{d}/stars.csv", "--width", "64", "--height", "64", "--fov-deg", "10"],
    "detect": ["{d}/a.fits"],
    "solve": ["{d}/a.fits"],
    "availability": ["--fov-deg", "10", "--pointings", "20", "--seed", "1"],
    "rate": ["{d}/a.fits", "{d}/b.fits", "--fov-deg", "10", "--dt-s", "1"],
    "track": ["{d}/frames", "--fov-deg", "10", "--out", "{d}/out/track.csv"],
    "calibrate": ["{d}/a.fits", "--fov-deg", "10", "--out", "{d}/out/camera.json"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_no_option_value_ends_as_a_fault_of_ours(command, inputs, monkeypatch):
    base = [a.format(d=inputs) for a in COMMANDS[command]]
    (inputs / "out").mkdir(exist_ok=True)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main([command, *base]) in (0, 1)  # the probe's base is valid: a 2 below is the bad value's
    faults = []
    for option, n in _valued_options(_parser_of(command, base, monkeypatch)):
        if option in ("--out", "--csv", "--wcs", "--profile", "--rig", "--dark", "--plot"):  # paths: tests of their own
            continue
        for value in BAD_VALUES:
            err = io.StringIO()
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                code = main([command, *base, option, *[value] * n])
            if code not in (0, 1, 2) or "Traceback" in err.getvalue():
                faults.append(f"{option} {value!r}: exit {code}: {err.getvalue().strip()[-200:]}")
    assert not faults, "\n".join(faults)
