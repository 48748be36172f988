"""A catalog epoch given as a Julian year is taken without importing astropy.time (0.3-0.4 s of a
command's start: ``startrack solve --epoch 2025.5``, the CLI's warm-up at the image's epoch)."""

from __future__ import annotations

import subprocess
import sys

import pytest
from astropy.time import Time

from startrack.errors import InvalidInputError
from startrack.identify._image_epoch import epoch_jyear


def test_a_year_is_taken_without_astropy():
    code = ("import sys\nfrom startrack.identify._image_epoch import epoch_jyear\n"
            "print(epoch_jyear(2025.5), epoch_jyear(None), 'astropy.time' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert done.stdout.split() == ["2025.5", "2000.0", "False"]


def test_a_time_and_bad_values_are_still_told_apart():
    assert epoch_jyear(Time("2025-07-02T12:00:00", scale="tdb")) == pytest.approx(2025.5, abs=1e-3)  # years
    for bad in ("2025", True, 5000.0, float("nan")):
        with pytest.raises(InvalidInputError, match="epoch must be an astropy Time or a Julian year"):
            epoch_jyear(bad)
