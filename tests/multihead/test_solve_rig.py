"""solve_rig on simulated star lists: joint accuracy against one head's, the joint pattern when no
head solves alone, the consistency angle of a wrong mounting, and misuse naming the head."""

from __future__ import annotations

import typing

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Status, solve_rig
from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.identify import MethodName
from startrack.multihead import IDENTIFIED_JOINTLY, RIG_METHODS, consistency_chi2
from startrack.multihead._joint import HeadMatch, fit_joint
from startrack.multihead._stars import HeadStars
from startrack.simulate._rig import rig_star_lists
from startrack.units import ARCSEC

from .rigs import TURN_X_90, split_rig, three_heads, two_heads

SIGMA_PX = 0.2
CORRECT = 60 * ARCSEC  # about one pixel: a wrong identification is off by degrees


def lists_at(rig, rot, rng, **kwargs):
    return {n: s.stars for n, s in rig_star_lists(rig, rot, max_mag=6.0, rng=rng, sigma_px=SIGMA_PX,
                                                    **kwargs).items()}


def error_components(truth: Rotation, estimate: Rotation) -> np.ndarray:
    """|rotation vector| components of truth * estimate^-1 in the frame the rotations map into."""
    return np.abs((truth * estimate.inv()).as_rotvec())


@pytest.fixture(scope="module")
def seeded_runs():
    """40 seeded random attitudes of the 90 deg two-head rig: (truth, lists, solution)."""
    rig, rng = two_heads(), np.random.default_rng(2024)
    runs = []
    for _ in range(40):
        truth = random_rotations(None, rng)
        stars = lists_at(rig, truth, rng)
        runs.append((truth, stars, solve_rig(stars, rig)))
    return rig, runs


def test_joint_roll_error_is_well_below_a_single_heads(seeded_runs):
    rig, runs = seeded_runs
    assert all(sol.solved for _, _, sol in runs)
    joint = np.array([error_components(t, s.rot_body_from_icrs) for t, _, s in runs])  # body = head a frame
    single = np.array([error_components(rig.head("a").rot_cam_from_icrs(t), s.heads["a"].rot_cam_from_icrs)
                       for t, _, s in runs])
    roll_ratio = np.sqrt(np.mean(joint[:, 2] ** 2)) / np.sqrt(np.mean(single[:, 2] ** 2))
    assert roll_ratio < 0.25  # measured 0.14 (2.4 vs 16.8 arcsec rms)
    assert np.sqrt(np.mean(joint[:, 2] ** 2)) < 4 * ARCSEC


def test_joint_total_error_is_below_the_better_heads(seeded_runs):
    rig, runs = seeded_runs
    joint = np.array([(t * s.rot_body_from_icrs.inv()).magnitude() for t, _, s in runs])
    for name in ("a", "b"):
        head = rig.head(name)
        own = np.array([(head.rot_cam_from_icrs(t) * s.heads[name].rot_cam_from_icrs.inv()).magnitude()
                        for t, _, s in runs])
        assert np.sqrt(np.mean(joint**2)) < 0.5 * np.sqrt(np.mean(own**2))


def test_joint_covariance_and_measured_noise_match_the_errors(seeded_runs):
    _, runs = seeded_runs
    roll = np.array([error_components(t, s.rot_body_from_icrs)[2] for t, _, s in runs])
    predicted = np.array([s.sigma_roll_arcsec["a"] for _, _, s in runs]) * ARCSEC
    assert 0.6 < np.sqrt(np.mean(roll**2)) / np.sqrt(np.mean(predicted**2)) < 1.6
    measured = np.array([s.centroid_sigma_px["b"] for _, _, s in runs])
    assert np.median(measured) == pytest.approx(SIGMA_PX, rel=0.2)
    for _, stars, sol in runs[:5]:  # every star of the lists is real: all are matched
        assert sol.heads_used == ("a", "b") and sol.n_matched == sum(len(s[0]) for s in stars.values())
        assert sol.consistency_deg < 0.02 and sol.inconsistent_heads == ()


def test_three_stars_in_each_of_two_heads_solve_jointly():
    rig, rng = two_heads(), np.random.default_rng(7)
    done = 0
    while done < 8:
        truth = random_rotations(None, rng)
        stars = lists_at(rig, truth, rng, max_stars=3)
        if min(len(s[0]) for s in stars.values()) < 3:
            continue
        done += 1
        sol = solve_rig(stars, rig)
        assert sol.solved and sol.mode == IDENTIFIED_JOINTLY, sol.reason
        assert sol.false_match_prob < 1e-6
        assert (truth * sol.rot_body_from_icrs.inv()).magnitude() < CORRECT
        assert not sol.heads["a"].solved or len(sol.matches["a"]) == 3  # 3 stars: too few to be solved alone


def test_a_wrong_mounting_is_detected_by_the_consistency_angle():
    true_rig, rng = two_heads(), np.random.default_rng(11)
    wrong = two_heads(Rotation.from_euler("z", 0.5, degrees=True) * TURN_X_90)
    for k in range(4):
        truth = random_rotations(None, rng)
        stars = lists_at(true_rig, truth, rng)
        if k % 2:  # head b has more stars and is identified first: the reference head still wins
            stars["a"] = tuple(v[:8] for v in stars["a"])
        sol = solve_rig(stars, wrong)
        assert sol.solved and sol.inconsistent_heads == ("b",) and sol.heads_used == ("a",)
        assert sol.consistency_deg == pytest.approx(0.5, abs=0.05)
        assert consistency_chi2(sol, wrong, "b") > 1e3
        own_a = sol.heads["a"].rot_cam_from_icrs  # the joint solution is head a's alone
        assert (own_a * sol.rot_body_from_icrs.inv()).magnitude() < 1e-3 * ARCSEC
        assert np.hypot(*error_components(truth, sol.rot_body_from_icrs)[:2]) < 10 * ARCSEC


def test_a_blinded_head_and_too_few_stars():
    rig, rng = three_heads(), np.random.default_rng(5)
    truth = random_rotations(None, rng)
    stars = lists_at(rig, truth, rng)
    stars["c"] = (np.zeros(0), np.zeros(0))
    sol = solve_rig(stars, rig)
    assert sol.solved and sol.heads_used == ("a", "b")
    assert sol.heads["c"].status is Status.TOO_FEW_STARS and "head 'c'" in sol.heads["c"].reason
    few = solve_rig({"a": tuple(v[:2] for v in stars["a"]), "b": tuple(v[:1] for v in stars["b"])}, rig)
    assert few.status is Status.TOO_FEW_STARS and few.rot_body_from_icrs is None and "a 2, b 1" in few.reason


def test_the_joint_fit_is_the_weighted_wahba_optimum():
    """Reference: scipy's align_vectors with weights 1 / sigma^2 on the same body-frame vectors."""
    rig, rng = two_heads(), np.random.default_rng(3)
    truth = random_rotations(None, rng)
    matches, sigma = [], {"a": 0.2, "b": 0.7}
    for head in rig:
        ref = Rotation.random(6, random_state=rng).apply([0, 0, 1]) * 0.02 + truth.inv().apply(head.boresight_body)
        ref /= np.linalg.norm(ref, axis=1, keepdims=True)
        cam = head.rot_cam_from_icrs(truth).apply(ref) + rng.normal(0, 1e-5, (6, 3))
        x, y = head.camera.vector_to_pixel(cam)
        stars = HeadStars.of(head, x, y)
        matches.append(HeadMatch(stars, np.arange(6), np.zeros(6, dtype=np.int64), ref))
    fit = fit_joint(matches, sigma)
    obs = np.concatenate([m.observed_body for m in matches])
    ref = np.concatenate([m.ref_icrs for m in matches])
    weights = np.repeat([1 / 0.2**2, 1 / 0.7**2], 6)
    expected, _ = Rotation.align_vectors(obs, ref, weights=weights)
    assert (fit.rot_body_from_icrs * expected.inv()).magnitude() < 1e-3 * ARCSEC


def test_misuse_names_the_head():
    rig = two_heads()
    star = (np.array([10.0, 20.0]), np.array([30.0, 40.0]))
    with pytest.raises(InvalidInputError, match="star list for head 'c', which is not in the rig"):
        solve_rig({"c": star}, rig)
    with pytest.raises(InvalidInputError, match="head 'b': star 1 at"):
        solve_rig({"b": (np.array([10.0, 2000.0]), np.array([30.0, 40.0]))}, rig)
    with pytest.raises(InvalidInputError, match="head 'a': give its stars as a tuple"):
        solve_rig({"a": np.zeros((2, 2))}, rig)
    with pytest.raises(InvalidInputError, match="'split' is the detector of split fields left, right"):
        solve_rig({"split": star}, split_rig())
    with pytest.raises(InvalidInputError, match="method must be one of quads, pyramid, .*van-bezooijen, got 'overlay'"):
        solve_rig({"a": star}, rig, method="overlay")  # needs a prior attitude, which a rig's lost-in-space has not
    assert "overlay" not in RIG_METHODS and set(RIG_METHODS) | {"overlay"} == set(typing.get_args(MethodName))


def test_two_heads_that_agree_outvote_the_reference_head():
    """Head a (the reference) given the stars of another pointing (a list given to the wrong head):
    before, the rig followed it and called the two agreeing heads inconsistent, degrees off."""
    rig, rng = three_heads(), np.random.default_rng(5)
    truth = random_rotations(None, rng)
    stars = lists_at(rig, truth, rng)
    stars["a"] = lists_at(rig, Rotation.from_euler("y", 40.0, degrees=True) * truth, rng)["a"]
    sol = solve_rig(stars, rig)
    assert sol.solved and sol.inconsistent_heads == ("a",), sol.inconsistent_heads
    assert (truth * sol.rot_body_from_icrs.inv()).magnitude() < CORRECT
