"""The streak fit's convergence test: a step is small when it is a small part of each end's,
the sag's and the blur's own 1-sigma (startrack.rate._streak_kernel._small_step)."""

import numpy as np
import pytest

from startrack.rate._streak_kernel import NPAR, SAG, SIG, _small_step


def _information(sigma_px):
    """J^T W J of independent parameters with these 1-sigma (px): the inverse of their variances."""
    return np.diag(1.0 / np.asarray(sigma_px, dtype=float) ** 2)


SIGMA = np.array([0.1, 0.1, 1.0, 1.0, 0.3, 0.5, 0.2, 0.05, 0.05])
"""cx, cy and hx, hy: a faint streak's centre is known to 0.1 px, its ends to about 1 px."""


def test_a_step_well_inside_each_sigma_is_small():
    step = np.zeros(NPAR)
    step[[0, 2]] = 0.01, 0.15  # an end moves 0.16 px of its ~1.0 px sigma
    assert _small_step(step, _information(SIGMA), 0.2)


@pytest.mark.parametrize("index, size", [(2, 0.5), (0, 0.25), (SAG, 0.1), (SIG, 0.02)])
def test_a_step_of_a_sizeable_part_of_a_sigma_is_not(index, size):
    step = np.zeros(NPAR)
    step[index] = size  # 0.5 px of an end (sigma ~1 px), 0.25 px of the centre, 0.33 sigma of the sag, 0.4 of the blur
    assert not _small_step(step, _information(SIGMA), 0.2)


def test_a_singular_system_is_never_converged():
    assert not _small_step(np.zeros(NPAR), np.zeros((NPAR, NPAR)), 0.2)
