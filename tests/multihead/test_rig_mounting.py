"""In-flight mounting calibration: a known offset recovered within its standard error, a drift
detected, a steady mounting not."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import solve_rig
from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.multihead._mounting import calibrate_mountings, recalibrated
from startrack.simulate._rig import rig_star_lists
from startrack.units import ARCSEC

from .rigs import TURN_X_90, two_heads

OFFSET = Rotation.from_rotvec(np.array([20.0, -30.0, 40.0]) * ARCSEC)  # head b's camera frame


def frames(true_rigs, nominal, seed: int):
    """One rig solve per true rig (one per frame), all against the nominal mountings."""
    rng = np.random.default_rng(seed)
    out = []
    for rig in true_rigs:
        body = random_rotations(None, rng)
        stars = {n: s.stars for n, s in rig_star_lists(rig, body, rng=rng, sigma_px=0.2).items()}
        out.append(solve_rig(stars, nominal))
    return out


def test_a_known_offset_is_recovered_within_its_uncertainty():
    nominal = two_heads()
    solutions = frames([two_heads(OFFSET * TURN_X_90)] * 30, nominal, seed=4)
    est = calibrate_mountings(solutions, nominal)["b"]
    assert est.n_frames == 30 and est.reference == "a"
    truth = OFFSET.as_rotvec()
    assert np.all(np.abs(est.offset_rad - truth) < 3.5 * est.standard_error_rad)
    assert np.all(est.standard_error_rad < 6 * ARCSEC) and est.offset_sigmas.max() > 5
    assert not est.drift_detected
    fixed = recalibrated(nominal, {"b": est})
    again = calibrate_mountings(solutions, fixed)["b"]
    assert np.all(np.abs(again.offset_rad) < 1e-9)


def test_a_drifting_mounting_is_detected_and_a_steady_one_is_not():
    nominal = two_heads()
    drifting = [two_heads(Rotation.from_rotvec([0.0, 0.0, k * 8.0 * ARCSEC]) * TURN_X_90) for k in range(24)]
    est = calibrate_mountings(frames(drifting, nominal, seed=6), nominal, times_s=np.arange(24) * 60.0)["b"]
    assert est.drift_detected
    assert est.drift_rad_s[2] == pytest.approx(8.0 * ARCSEC / 60.0, rel=0.3)
    steady = calibrate_mountings(frames([nominal] * 24, nominal, seed=6), nominal)["b"]
    assert not steady.drift_detected and np.all(steady.offset_sigmas < 4)
    with pytest.raises(InvalidInputError, match="times_s"):
        calibrate_mountings(frames([nominal] * 3, nominal, seed=1), nominal, times_s=[0.0, 1.0])
