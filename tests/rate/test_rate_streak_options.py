"""StreakOptions refuses the settings the streak path cannot use, naming the setting."""

import math

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.rate import StreakOptions


def test_the_defaults_and_legal_values_are_taken():
    StreakOptions()
    StreakOptions(lis_streaks=np.int64(10), psf_sigma_px=np.float32(1.5), fit_alpha=np.bool_(True),
                  pixel_aspect=None, gain_e_per_adu=2.0, enough_rate_uncertainty=0, catalog_max_mag=-1.0)


@pytest.mark.parametrize(("name", "value"), [
    ("enough_rate_uncertainty", math.nan), ("enough_rate_uncertainty", -0.01),
    ("max_rate_uncertainty", 0.0), ("max_rate_uncertainty", math.inf), ("max_birge", math.nan),
    ("psf_sigma_px", -1.0), ("pixel_aspect", 0.0), ("gain_e_per_adu", math.inf), ("line_time_s", -1e-6),
    ("catalog_max_mag", math.nan), ("catalog_max_mag", "7.5"), ("lis_streaks", 2), ("max_streaks", 12.0),
    ("min_streaks", True), ("fit_alpha", 1), ("psf_sigma_px", 1 + 0j),
])
def test_a_bad_setting_is_refused_by_name(name, value):
    with pytest.raises(InvalidInputError, match=f"^{name} must be"):
        StreakOptions(**{name: value})
