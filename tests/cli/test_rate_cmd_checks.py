"""``startrack rate`` refuses options that are not finite or out of their range, naming them."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.cli import main
from startrack.io import write_fits


@pytest.fixture
def image(tmp_path):
    path = tmp_path / "flat.fits"
    write_fits(path, np.full((64, 64), 100, dtype=np.uint16))
    return str(path)


@pytest.mark.parametrize(("options", "named"), [
    (["--exposure-s", "0.1", "--bias-px", "nan"], "--bias-px"),
    (["--exposure-s", "0.1", "--detector", "harris", "--bias-px", "nan"], "--bias-px"),
    (["--exposure-s", "0.1", "--bias-px", "inf"], "--bias-px"),
    (["--exposure-s", "0.1", "--bias-px", "50"], "--bias-px"),
    (["--exposure-s", "0.1", "--prior-rate-deg-s", "nan", "0", "0"], "--prior-rate-deg-s"),
    (["--exposure-s", "0.1", "--prior-rate-deg-s", "0", "0", "0"], "--prior-rate-deg-s"),
    (["--exposure-s", "1e-9"], "--exposure-s"),
    (["--exposure-s", "nan"], "--exposure-s"),
    (["--exposure-s", "-1"], "--exposure-s"),
    (["--exposure-s", "0.1", "--max-motion-deg", "0"], "--max-motion-deg"),
])
def test_one_image_options_are_checked(image, capsys, options, named):
    assert main(["rate", image, "--fov-deg", "12", *options]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err


@pytest.mark.parametrize(("options", "named"), [
    (["--dt-s", "0"], "--dt-s"),
    (["--dt-s", "nan"], "--dt-s"),
    (["--dt-s", "1e-9"], "--dt-s"),
    (["--dt-s", "0.2", "--max-motion-deg", "-1"], "--max-motion-deg"),
    (["--dt-s", "0.2", "--max-motion-deg", "inf"], "--max-motion-deg"),
])
def test_image_pair_options_are_checked(image, capsys, options, named):
    assert main(["rate", image, image, "--fov-deg", "12", *options]) == 2
    assert named in capsys.readouterr().err


def test_a_valid_range_is_stated(image, capsys):
    assert main(["rate", image, "--fov-deg", "12", "--exposure-s", "1e-9"]) == 2
    assert "0.0001 to 3600 s" in capsys.readouterr().err
