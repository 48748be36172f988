"""What the typing of issue 21 made explicit: the matcher names in one Literal, a tiled
background's grids as one TileGrid, a streak solution's fields read only from a StreakSolution."""

import numpy as np
import pytest

from startrack.detect import _background as background
from startrack.errors import InvalidInputError
from startrack.identify._registry import MATCHERS, METHOD_NAMES, OPTIONS, check_method, options_for, prepare_matcher
from startrack.io._solution_json import solution_to_dict, streak_fields
from startrack.results import AttitudeSolution, Status


def test_the_method_literal_names_every_matcher_and_its_options_in_their_order():
    assert list(METHOD_NAMES) == list(MATCHERS) == list(OPTIONS)
    assert all(check_method(name) == name for name in METHOD_NAMES)


@pytest.mark.parametrize("call", [lambda: check_method("quad"), lambda: options_for("quad"),
                                  lambda: prepare_matcher("quad", None)])
def test_an_unknown_method_is_refused_naming_the_valid_ones(call):
    with pytest.raises(InvalidInputError, match="method must be one of quads, pyramid, .*overlay, got 'quad'"):
        call()


def test_a_tiled_model_holds_its_grids_in_one_tile_grid_and_a_constant_one_none():
    rng = np.random.default_rng(3)
    image = 100.0 + rng.normal(0.0, 2.0, (64, 96))
    tiled = background.tiled_background(image, 16)
    tiles = tiled.tiles
    assert tiles is not None and tiled.is_tiled
    assert tiles.level.shape == tiles.noise.shape == tiles.clutter.shape == (4, 6)
    assert (tiles.centres_y.shape, tiles.centres_x.shape) == ((4,), (6,))
    floored = background.with_noise_floor(tiled, 50.0)
    assert floored.tiles is not None and floored.tiles.noise.min() == 50.0 and floored.tiles.level is tiles.level
    flat = background.global_background(image)
    assert flat.tiles is None
    # the constant model's level at any point is its level (counts), the tiled one's near 100 counts
    assert flat.level_at(np.array([3.0]), np.array([4.0]))[0] == flat.level
    assert tiled.level_at(np.array([3.0]), np.array([4.0]))[0] == pytest.approx(100.0, abs=2.0)


def test_a_point_solution_has_no_streak_fields_and_writes_none():
    failed = AttitudeSolution(status=Status.NO_MATCH, reason="no match")
    assert streak_fields(failed) == {}
    out = solution_to_dict(failed)
    assert out["status"] == Status.NO_MATCH.value and "mode" not in out
