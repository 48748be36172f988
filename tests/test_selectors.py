"""Issue 21 item 2: every string selector is a Literal checked at its entry point, and a stage's
options of the wrong class are refused; each refusal names the parameter, the value (or class)
given and what would be valid. One test of a wrong choice and one of the right ones per selector."""

import dataclasses
import typing

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.attitude._wahba import METHODS as WAHBA_METHODS
from startrack.attitude._wahba import WahbaMethod, solve_wahba
from startrack.detect._denoise import DENOISE_METHODS
from startrack.detect._detector import StarDetector
from startrack.detect._settings import DetectionSettings
from startrack.errors import InvalidInputError
from startrack.identify._options_base import MatcherOptionsBase
from startrack.identify._registry import METHOD_NAMES, OPTIONS, MethodName, check_method, check_options
from startrack.rate._endpoints import DETECTORS, CornerDetector, check_detector, cornerness
from startrack.rate._rso import INDICATORS, IndicatorName
from startrack.rate._streak_rate import METHODS as ENDPOINT_METHODS
from startrack.rate._streak_rate import EndpointMethod, check_endpoint_method, measure_streaks
from startrack.rate._streak_solve import StreakOptions, checked_options, solve_streaked
from startrack.solve import solve_image, solve_stars
from startrack.track._tracker import (
    LOST_IN_SPACE,
    POINT_MODE,
    STEP_MODES,
    STREAK_LOST_IN_SPACE,
    STREAK_MODE,
    STREAK_TRACKING,
    TRACKING,
    FrameMode,
    Tracker,
    TrackerOptions,
)


def _names_all(message: str, parameter: str, bad: str, valid) -> None:
    assert parameter in message and repr(bad) in message, message
    missing = [v for v in valid if v not in message]
    assert not missing, f"{message!r} does not name {missing}"


# --- the Literals hold the names the checks accept ----------------------------------------------
@pytest.mark.parametrize("literal, names", [(MethodName, METHOD_NAMES), (WahbaMethod, WAHBA_METHODS),
                                            (CornerDetector, DETECTORS), (EndpointMethod, ENDPOINT_METHODS),
                                            (IndicatorName, INDICATORS)])
def test_each_literal_lists_the_names_of_its_tuple_in_order(literal, names):
    assert typing.get_args(literal) == tuple(names) and len(set(names)) == len(names)


# --- identify: method names ---------------------------------------------------------------------
def test_a_wrong_matcher_name_is_refused_by_check_method_and_the_entry_points():
    with pytest.raises(InvalidInputError) as err:
        check_method("Quads")
    _names_all(str(err.value), "method", "Quads", METHOD_NAMES)
    for entry in (lambda: solve_stars([1.0, 2.0], [1.0, 2.0], width=10, height=10, method="quad"),
                  lambda: solve_image(np.zeros((16, 16)), method="quad")):
        with pytest.raises(InvalidInputError) as err:
            entry()
        _names_all(str(err.value), "method", "quad", METHOD_NAMES)


@pytest.mark.parametrize("value", [np.zeros(3), np.array(["quads", "angle"]), ["quads"], 1])
def test_a_selector_that_is_not_a_string_is_refused_not_compared(value):
    # an array compared with each name made "the truth value of an array ... is ambiguous", a bare ValueError
    for entry in (lambda: solve_stars([1.0, 2.0], [1.0, 2.0], width=10, height=10, method=value),
                  lambda: solve_stars([1.0, 2.0], [1.0, 2.0], width=10, height=10, parity=value)):
        with pytest.raises(InvalidInputError, match="must be one of"):
            entry()


@pytest.mark.parametrize("method", METHOD_NAMES)
def test_every_matcher_name_passes_with_its_own_options_class(method):
    assert check_method(method) == method
    assert check_options(method, None) == method
    assert check_options(method, OPTIONS[method]()) == method


# --- identify: options class against the method -------------------------------------------------
def test_every_matcher_options_class_subclasses_the_one_base():
    for method in METHOD_NAMES:
        cls = OPTIONS[method]
        assert issubclass(cls, MatcherOptionsBase), cls
        shared = cls()
        assert (shared.verify_stars, shared.match_radius_px, shared.max_false_match_prob) == (40, None, 1e-6)


def _foreign(method: str) -> MatcherOptionsBase:
    """Options of another matcher, of a class that is not the method's (nor a subclass of it)."""
    expected = OPTIONS[method]
    other = next(OPTIONS[m] for m in METHOD_NAMES if not issubclass(OPTIONS[m], expected))
    return other()


@pytest.mark.parametrize("method", METHOD_NAMES)
def test_options_of_another_matchers_class_are_refused_naming_the_method_and_both_classes(method):
    wrong = _foreign(method)
    with pytest.raises(InvalidInputError) as err:
        check_options(method, wrong)
    message = str(err.value)
    assert method in message and OPTIONS[method].__name__ in message and type(wrong).__name__ in message, message


def test_the_entry_points_refuse_options_of_the_wrong_class_before_any_work():
    wrong = OPTIONS["pyramid"]()
    for entry in (lambda: solve_stars([1.0, 2.0], [1.0, 2.0], width=10, height=10, options=wrong),
                  lambda: solve_image(np.zeros((16, 16)), options=wrong),
                  lambda: solve_stars([1.0, 2.0], [1.0, 2.0], width=10, height=10, options=StreakOptions())):
        with pytest.raises(InvalidInputError, match="options for the quads matcher must be a MatcherOptions.*got a "):
            entry()


# --- attitude: Wahba solvers ----------------------------------------------------------------------
def _wahba_problem():
    rng = np.random.default_rng(21)
    ref = rng.normal(size=(6, 3))
    ref /= np.linalg.norm(ref, axis=1, keepdims=True)
    truth = Rotation.from_rotvec([0.1, -0.2, 0.3])
    return truth.apply(ref), ref, truth


def test_a_wrong_wahba_method_is_refused_naming_the_valid_ones():
    obs, ref, _ = _wahba_problem()
    with pytest.raises(InvalidInputError) as err:
        solve_wahba(obs, ref, method="Quest")
    _names_all(str(err.value), "method", "Quest", WAHBA_METHODS)


@pytest.mark.parametrize("method", WAHBA_METHODS)
def test_every_wahba_method_runs_under_its_name(method):
    obs, ref, truth = _wahba_problem()
    rotation = solve_wahba(obs, ref, method=method).rotation
    assert isinstance(rotation, Rotation)
    assert (rotation * truth.inv()).magnitude() < 1e-6  # rad: noise-free vectors, so every solver finds the truth


# --- detect: StarDetector selectors ---------------------------------------------------------------
_DETECTOR_SELECTORS = [(name, typing.get_args(hint)) for name, hint in typing.get_type_hints(StarDetector).items()
                       if typing.get_origin(hint) is typing.Literal]


def test_the_star_detector_has_literal_selectors():
    expected = {"background", "threshold", "grouping", "centroid", "denoise", "kernel"}
    assert expected <= {name for name, _ in _DETECTOR_SELECTORS}


def test_a_wrong_denoise_method_is_refused_at_construction_naming_the_valid_ones():
    assert typing.get_args(typing.get_type_hints(StarDetector)["denoise"]) == DENOISE_METHODS
    for build in (lambda: StarDetector(denoise="median"),
                  lambda: dataclasses.replace(StarDetector(), denoise="median"),
                  lambda: DetectionSettings(denoise="median")):
        with pytest.raises(InvalidInputError) as err:
            build()
        _names_all(str(err.value), "denoise", "median", DENOISE_METHODS)


@pytest.mark.parametrize("name, valid", _DETECTOR_SELECTORS)
def test_a_wrong_star_detector_selector_is_refused_and_every_right_one_accepted(name, valid):
    with pytest.raises(InvalidInputError) as err:
        StarDetector(**{name: "no-such-" + name})
    _names_all(str(err.value), name, "no-such-" + name, valid)
    for value in valid:
        assert getattr(StarDetector(**{name: value}), name) == value


# --- rate: endpoint methods, the streak path's options --------------------------------------------
def test_a_wrong_corner_detector_is_refused_by_its_check_and_cornerness():
    for bad, call in (("segment", lambda: check_detector("segment")),
                      ("Harris", lambda: cornerness(np.zeros((8, 8)), "Harris"))):
        with pytest.raises(InvalidInputError) as err:
            call()
        _names_all(str(err.value), "detector", bad, DETECTORS)


@pytest.mark.parametrize("detector", DETECTORS)
def test_every_corner_detector_name_is_accepted(detector):
    assert check_detector(detector) == detector
    assert cornerness(np.ones((8, 8)), detector).shape == (8, 8)


def test_a_wrong_endpoint_method_is_refused_naming_the_segment_fit_and_the_detectors():
    with pytest.raises(InvalidInputError) as err:
        measure_streaks(np.zeros((32, 32)), detector="segments")
    _names_all(str(err.value), "detector", "segments", ENDPOINT_METHODS)
    assert all(check_endpoint_method(name) == name for name in ENDPOINT_METHODS)


def test_the_streak_path_refuses_options_of_another_class_and_a_wrong_matcher_name():
    assert checked_options(None) == StreakOptions()
    mine = StreakOptions(lis_streaks=10)
    assert checked_options(mine) is mine
    with pytest.raises(InvalidInputError, match="options of the streak path must be a startrack.rate.StreakOptions, "
                                                "got a TrackerOptions"):
        solve_streaked(np.zeros((32, 32)), fov_deg=10.0, options=TrackerOptions())
    with pytest.raises(InvalidInputError) as err:
        solve_streaked(np.zeros((32, 32)), fov_deg=10.0, method="quad")
    _names_all(str(err.value), "method", "quad", METHOD_NAMES)


# --- track: the Tracker's options and its modes ---------------------------------------------------
def test_the_tracker_refuses_options_of_another_class_naming_both():
    with pytest.raises(InvalidInputError, match="must be a startrack.track.TrackerOptions, got a "
                                                "StreakOptions"):
        Tracker(width=64, height=64, fov_deg=10.0, options=StreakOptions())
    with pytest.raises(InvalidInputError, match="TrackerOptions.streak must be a startrack.rate.StreakOptions, got a "
                                                "MatcherOptions"):
        TrackerOptions(streak=OPTIONS["quads"]())


def test_the_tracker_takes_its_own_options_and_names_its_modes_by_their_literals():
    options = TrackerOptions(streak=StreakOptions(lis_streaks=10))
    tracker = Tracker(width=64, height=64, fov_deg=10.0, options=options)
    assert tracker.options is options and tracker.mode == POINT_MODE
    assert STEP_MODES == (LOST_IN_SPACE, TRACKING, STREAK_LOST_IN_SPACE, STREAK_TRACKING)
    assert typing.get_args(FrameMode) == (POINT_MODE, STREAK_MODE)
