"""A search that found nothing says what it took as known that the user may have got wrong: a
field of view given (searched within 3 %), a calibrated camera, the image's parity."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Camera, Status, solve_stars
from startrack.frames import random_rotations
from startrack.identify._field_stars import field_stars

CAMERA = Camera.from_fov(1024, 1024, 15.0)
FOV_HINT = "the field of view was searched within 3% of the one given"
PARITY_HINT = "a mirror image (flipped, or y up) needs parity 'either'"


def _star_list() -> tuple[np.ndarray, np.ndarray]:
    """Catalog stars to V 7 (J2000) of a 15 deg field at a random attitude, brightest first."""
    v_cam = random_rotations(rng=np.random.default_rng(11)).apply(field_stars(7.0, 2000.0).vectors)
    x, y = CAMERA.vector_to_pixel(v_cam[v_cam[:, 2] > 0.9])
    inside = CAMERA.in_image(x, y)
    return x[inside], y[inside]


@pytest.mark.parametrize(("given", "hints"), [
    ({"fov_deg": 12.0}, (FOV_HINT, PARITY_HINT)),  # 20 % off: outside what a given field allows
    ({"camera": Camera.from_fov(1024, 1024, 12.0)}, ("taken as calibrated", PARITY_HINT)),
    ({"fov_range_deg": (11.0, 12.0)}, (PARITY_HINT,)),
])
def test_a_failed_search_names_what_it_took_as_known(given, hints):
    x, y = _star_list()
    solution = solve_stars(x, y, width=1024, height=1024, **given)
    assert solution.status is Status.NO_MATCH
    assert [hint in solution.reason for hint in (FOV_HINT, "taken as calibrated", PARITY_HINT)] == \
        [hint in hints for hint in (FOV_HINT, "taken as calibrated", PARITY_HINT)], solution.reason


def test_a_mirror_search_that_fails_does_not_point_at_parity():
    x, y = _star_list()
    solution = solve_stars(x, y, width=1024, height=1024, fov_range_deg=(11.0, 12.0), parity="either")
    assert solution.status is Status.NO_MATCH and "parity" not in solution.reason, solution.reason


def test_a_narrow_range_is_not_taken_for_a_field_of_view_given():
    """Found in review: a range of (11, 11.5) deg was reported as a field of view given."""
    x, y = _star_list()
    solution = solve_stars(x, y, width=1024, height=1024, fov_range_deg=(11.0, 11.5))
    assert solution.status is Status.NO_MATCH and FOV_HINT not in solution.reason, solution.reason


@pytest.mark.parametrize(("method", "offered"), [("quads", True), ("pyramid", False), ("angle", False)])
def test_parity_is_offered_only_by_the_matcher_that_can_search_mirror_images(method, offered):
    """Found in review: the other matchers refuse parity 'either', which the hint proposed."""
    from types import SimpleNamespace

    from startrack import Camera
    from startrack.solve import _no_match_hints

    request = SimpleNamespace(fov_range_deg=(11.0, 12.0), focal_range=(1.0, 2.0), parity="normal",
                              camera=Camera.from_fov(1024, 1024, 11.5))
    assert (PARITY_HINT in _no_match_hints(request, method)) is offered


def test_a_narrow_field_that_fails_says_how_few_catalog_stars_it_holds():
    from startrack.solve import _narrow_field_hint

    # 117,955 stars over 41,253 deg2: 2.86 per deg2, so 1.0 x 0.8 deg holds 2 and 10 x 8 deg 229
    hint = _narrow_field_hint(Camera.from_fov(1000, 800, 1.0), 1.0)
    assert hint is not None and "1 x 0.8 deg holds 2 Hipparcos stars on average" in hint
    assert _narrow_field_hint(Camera.from_fov(1000, 800, 10.0), 10.0) is None
    # a pixel twice as high on the sky doubles the field's height
    tall = _narrow_field_hint(Camera.from_fov(1000, 800, 1.0, pixel_aspect=2.0), 1.0)
    assert tall is not None and "1 x 1.6 deg holds 5" in tall


def _no_database(*args, **kwargs):
    raise AssertionError("a pattern database was loaded for a solve that could not succeed")


def test_a_field_too_sparse_for_the_catalog_fails_before_any_database(monkeypatch):
    """Found by a probe: a 0.7 deg field given spent 34 s building a pattern database first."""
    import startrack.solve as solve

    monkeypatch.setattr(solve, "prepare_matcher", _no_database)
    x, y = np.array([100.0, 400.0, 700.0, 250.0, 820.0, 530.0]), np.array([90.0, 600.0, 300.0, 700.0, 120.0, 420.0])
    solution = solve_stars(x, y, width=1000, height=800, fov_deg=0.7)
    assert solution.status is Status.NO_MATCH, solution.reason
    assert solution.reason.startswith("not searched: a field of 0.721 x 0.577 deg holds 1 Hipparcos stars")
    assert not solution.solved and solution.solve_time_s == 0.0


def test_a_list_of_three_stars_fails_before_any_database(monkeypatch):
    import startrack.solve as solve

    monkeypatch.setattr(solve, "prepare_matcher", _no_database)
    solution = solve_stars([10.0, 500.0, 900.0], [20.0, 400.0, 700.0], width=1000, height=800, fov_deg=12.0)
    assert solution.status is Status.TOO_FEW_STARS
    assert solution.reason == "lost-in-space identification needs at least 4 stars, got 3"


@pytest.mark.parametrize(("fov_deg", "sparse"), [(0.5, True), (0.72, True), (0.73, False), (3.0, False)])
def test_the_sparse_field_limit_is_where_a_field_holds_1_5_catalog_stars(fov_deg, sparse):
    from startrack.solve import MIN_CATALOG_STARS, expected_catalog_stars, too_sparse_to_solve

    assert too_sparse_to_solve(fov_deg) is sparse
    assert (expected_catalog_stars(fov_deg, fov_deg) < MIN_CATALOG_STARS) is sparse
    # a field twice as high holds twice as many
    assert too_sparse_to_solve(0.6, 2.0) is False and too_sparse_to_solve(0.6, 1.0) is True


def test_the_command_builds_no_database_for_a_field_too_sparse(monkeypatch):
    import startrack.identify as identify
    from startrack.cli._progress import ensure_database

    monkeypatch.setattr(identify, "load_database", _no_database)
    ensure_database((0.5, 0.6))  # nothing loaded, nothing built
    with pytest.raises(AssertionError, match="pattern database was loaded"):
        ensure_database((9.0, 11.0))


def test_the_command_judges_a_tall_field_as_the_solve_does(monkeypatch):
    """A portrait field 0.62 deg wide and 1.3 high holds 2.3 stars on average: the solve searches
    it, so the command builds its database (found in review: the command took every field square)."""
    import startrack.identify as identify
    from startrack.cli._progress import ensure_database_for
    from startrack.solve import too_sparse_to_solve

    assert too_sparse_to_solve(0.62) and not too_sparse_to_solve(0.62, 1.3 / 0.62)
    monkeypatch.setattr(identify, "load_database", _no_database)
    ensure_database_for(fov_deg=0.6)  # a square field: nothing built
    with pytest.raises(AssertionError, match="pattern database was loaded"):
        ensure_database_for(fov_deg=0.6, height_ratio=2.1)
    with pytest.raises(AssertionError, match="pattern database was loaded"):
        ensure_database_for(camera=Camera.from_fov(600, 1260, 0.6))
