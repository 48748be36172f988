"""Pieces of the streak path that were rewritten for speed, against their plain definitions: the
compiled Rodrigues rotation of the joint fit, the crowding test of predicted streaks, and the
frame prepared once for all of a solve's fits."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.rate import fit_streaks
from startrack.rate._streak_fit import fit_pixels, saturation_level, verdicts
from startrack.rate._streak_kernel import NGEO, arc_value, geometry
from startrack.rate._streak_model import rotate
from startrack.rate._streak_predict import CROWDED_PX, PATH_SAMPLES, crowded


@pytest.mark.parametrize(("v_shape", "t_shape"),
                         [((5, 3), (5, 3)), ((2, 4, 1, 3), (2, 4, 7, 3)), ((1, 6, 3), (3, 1, 3))])
def test_rotate_is_the_rotation_by_minus_theta(v_shape, t_shape):
    rng = np.random.default_rng(3)
    vectors, theta = rng.normal(size=v_shape), 0.3 * rng.normal(size=t_shape)
    theta.reshape(-1, 3)[0] = 0.0  # no rotation at all
    got = rotate(vectors, theta)
    v, t = np.broadcast_arrays(vectors, theta)
    want = Rotation.from_rotvec(-t.reshape(-1, 3)).apply(v.reshape(-1, 3)).reshape(got.shape)
    assert got.shape == np.broadcast_shapes(v_shape, t_shape)
    assert np.max(np.abs(got - want)) < 1e-14 * np.max(np.abs(want))  # relative, of unitless vectors


def _crowded_by_definition(predicted, candidates, neighbours, blur_px):
    f = np.linspace(0.0, 1.0, PATH_SAMPLES)[:, None]
    paths = predicted[:, None, 0:2] * (1 - f) + predicted[:, None, 2:4] * f
    radius = CROWDED_PX + 4.0 * blur_px
    out = []
    for c in candidates:
        others = [n for n in neighbours if n != c]
        gaps = [np.min(np.linalg.norm(paths[c][:, None] - paths[n][None], axis=2)) for n in others]
        out.append(bool(others) and min(gaps) <= radius)
    return np.array(out, dtype=bool)


def test_crowded_matches_its_definition():
    rng = np.random.default_rng(11)
    for _ in range(60):
        s = int(rng.integers(2, 40))
        start = rng.uniform(0.0, 300.0, (s, 2))
        end = start + rng.normal(size=(s, 2)) * rng.uniform(2.0, 80.0)
        predicted = np.hstack([start, end, 0.5 * (start + end)])
        candidates = np.sort(rng.choice(s, int(rng.integers(0, s + 1)), replace=False))
        neighbours = np.union1d(candidates, rng.choice(s, int(rng.integers(0, s + 1)), replace=False))
        blur = float(rng.uniform(0.5, 3.0))
        got = crowded(predicted, candidates, neighbours, blur)
        want = _crowded_by_definition(predicted, candidates, neighbours, blur)
        assert np.array_equal(got, want)


def test_fit_pixels_keep_the_frames_saturation():
    truth = np.array([60.0, 50.0, 30.0, 10.0, 0.0, 5000.0, 0.0, 100.0, 1.2])  # saturates a 12-bit ADC
    geo = np.empty(NGEO)
    geometry(truth, geo)
    model = np.array([[arc_value(float(x), float(y), geo) for x in range(120)] for y in range(100)])
    noisy = model + np.random.default_rng(2).normal(0.0, 5.0, model.shape)
    raw = np.clip(np.rint(noisy), 0, 4095).astype(np.uint16)
    pixels, saturation = fit_pixels(raw)
    assert pixels.dtype == np.float64 and pixels.flags.c_contiguous and np.array_equal(pixels, raw)
    assert saturation == saturation_level(raw) == 4095.0
    assert fit_pixels(noisy)[1] == np.inf  # a float frame has no ADC ceiling
    guess = truth.copy()
    guess[5] = 3000.0
    args = (guess[None], np.array([8.0]), np.array([6.0]))
    direct = fit_streaks(raw, *args, noise=5.0)
    prepared = fit_streaks(pixels, *args, noise=5.0, saturation=saturation)
    assert np.array_equal(direct.params, prepared.params) and direct.ok[0]


def test_verdicts_name_the_first_test_each_fit_fails():
    good = np.array([60.0, 50.0, 20.0, 5.0, 0.0, 300.0, 0.0, 100.0, 1.2])  # in a 100 x 120 px frame
    cov = np.eye(9) * 0.01

    def case(flag=0, **changes):
        p, c = good.copy(), cov.copy()
        for name, value in changes.items():
            if name == "amp_var":
                c[5, 5] = value
            elif name == "end_var":
                c[0, 0] = value
            else:
                p["cx cy hx hy sag a g b s".split().index(name)] = value
        return p, c, flag

    cases = [(case(), ""), (case(flag=3), "singular fit"), (case(flag=1, s=9.0), "the fit did not converge"),
             (case(s=5.0), "fitted blur 5.00 px: not one star's streak"),
             (case(hx=1.0, hy=0.0), "streak 2.0 px long, shorter than 3 px"),
             (case(amp_var=2000.0), "too faint"),
             (case(cx=20.0), "an end at the image border: the star entered or left the field"),
             (case(end_var=5.0), "ends less precise than 2 px"), (case(end_var=np.nan), "ends less precise than 2 px")]
    params = np.array([c[0][0] for c in cases])
    covs = np.array([c[0][1] for c in cases])
    flags = np.array([c[0][2] for c in cases])
    assert verdicts(params, covs, flags, (100, 120)) == tuple(want for _, want in cases)
