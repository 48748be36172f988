"""Rig availability: one head reproduces the single-camera star counts; more heads and the joint
solution are available more often; exclusion zones take heads out."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import CameraRig, RigHead
from startrack.analysis._availability import star_counts
from startrack.errors import InvalidInputError
from startrack.multihead._availability import rig_availability
from startrack.multihead._exclusion import dawn_dusk_bodies

from .rigs import CAMERA, three_heads, two_heads


def test_one_head_counts_what_star_counts_counts():
    rig = CameraRig([RigHead("a", CAMERA, Rotation.identity())])
    single = star_counts(CAMERA, 5.0, 3000, rng=3)
    np.testing.assert_array_equal(rig_availability(rig, 5.0, 3000, rng=3).counts["a"], single.counts)


def test_more_heads_more_often_and_the_joint_at_least_as_often():
    one = rig_availability(CameraRig([RigHead("a", CAMERA, Rotation.identity())]), 5.0, 4000, rng=1)
    two = rig_availability(two_heads(), 5.0, 4000, rng=1)
    three = rig_availability(three_heads(), 5.0, 4000, rng=1)
    assert np.array_equal(one.counts["a"], two.counts["a"])  # same body attitudes, head a the same
    f1, f2, f3 = (np.mean(r.any_head) for r in (one, two, three))
    assert f1 < f2 < f3
    assert np.all(two.joint >= two.any_head)
    assert f2 == pytest.approx(1 - (1 - f1) ** 2, abs=0.05)  # two heads 90 deg apart: nearly independent fields
    s = three.summary()
    assert set(s["heads"]) == {"a", "b", "c"} and s["joint"] >= s["any_head"]


def test_exclusion_takes_heads_out():
    bodies = dawn_dusk_bodies("2025-03-20T12:00:00", 500.0)
    free = rig_availability(two_heads(), 5.0, 4000, rng=2)
    excluded = rig_availability(two_heads(), 5.0, 4000, rng=2, bodies=bodies)
    # the Earth seen from 500 km: 68 deg radius + 20 deg limb exclusion cover 48 % of the sky, the Sun 7 %
    assert np.mean(excluded.blinded["a"]) == pytest.approx(0.52, abs=0.04)
    assert np.all(excluded.counts["a"][excluded.blinded["a"]] == 0)
    assert np.mean(excluded.any_head) < np.mean(free.any_head)
    with pytest.raises(InvalidInputError, match="n_pointings"):
        rig_availability(two_heads(), 5.0, 0)
