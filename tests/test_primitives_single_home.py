"""One home for each primitive (issue 21 item 3): the epoch converter (``catalog.epoch_jyear``), the
angle/chord pair (``catalog.chord``) and the cone query over a k-d tree (``catalog.cone.query_cone``),
what each checks, and that the rest of ``src/startrack`` uses them instead of its own copy."""

from __future__ import annotations

import ast
import math
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from erfa import ErfaWarning
from scipy.spatial import cKDTree

import startrack.catalog as catalog_pkg
from startrack.catalog import (
    ConeIndex,
    StarCatalog,
    angle_from_chord,
    chord_from_angle,
    epoch_jyear,
    jyear_tdb,
    query_cone,
)
from startrack.errors import InvalidInputError
from startrack.frames import radec_to_vector
from startrack.identify import _image_epoch as image_epoch

SRC = Path(__file__).resolve().parents[1] / "src" / "startrack"


def _tiny_catalog() -> StarCatalog:
    return StarCatalog.from_positions(ra_rad=[0.1, 0.2], dec_rad=[0.0, 0.1], v_mag=[1.0, 2.0])


def test_the_epoch_converter_takes_a_year_and_a_time():
    assert epoch_jyear(2025.5) == 2025.5 and epoch_jyear(np.float32(2000)) == 2000.0
    when = Time("2024-01-01T00:00:00", scale="utc")
    assert epoch_jyear(when) == jyear_tdb(when) == float(when.tdb.jyear)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ErfaWarning)
        far = Time("2290-06-01T00:00:00", scale="utc")  # past the leap-second table
    assert epoch_jyear(far) == pytest.approx(2290.41, abs=0.01)  # years; ERFA's warning (an error here) silenced


@pytest.mark.parametrize("bad", [None, True, "2025", "soon", float("nan"), float("inf"), 5000.0, 999.0, [2020.0]])
def test_the_epoch_converter_refuses_bad_input_naming_the_parameter(bad):
    with pytest.raises(InvalidInputError, match=r"^when_jyear must be an astropy Time or a Julian year"):
        epoch_jyear(bad, "when_jyear")


def test_an_array_of_times_is_refused_naming_the_parameter():
    with pytest.raises(InvalidInputError, match="when_jyear must be a single time, got an array of 2"):
        epoch_jyear(Time([2020.0, 2021.0], format="jyear", scale="tdb"), "when_jyear")


def test_the_catalog_the_simulator_and_the_solver_use_the_one_converter():
    from startrack.simulate import SkyModel

    cat = _tiny_catalog()
    when = Time("2024-03-01T00:00:00", scale="utc")
    np.testing.assert_array_equal(cat.vectors(when), cat.vectors(epoch_jyear(when)))
    assert cat.propagated(when).epoch_jyear == epoch_jyear(when)
    for call in (lambda: cat.vectors("2025"), lambda: cat.propagated(5000.0),
                 lambda: SkyModel.from_catalog(max_mag=3.0, epoch_jyear=True)):
        with pytest.raises(InvalidInputError, match="^epoch_jyear must be an astropy Time or a Julian year"):
            call()
    assert image_epoch.epoch_jyear(None) == image_epoch.DEFAULT_EPOCH_JYEAR == 2000.0
    assert image_epoch.epoch_jyear(when) == epoch_jyear(when)
    with pytest.raises(InvalidInputError, match="^epoch must be an astropy Time"):
        image_epoch.epoch_jyear("2025")


def test_the_chord_pair_round_trips_and_checks_its_angle():
    angles = np.array([0.0, 1e-9, 0.01, 1.0, 3.0, math.pi])
    chords = np.array([chord_from_angle(a, "a", allow_zero=True) for a in angles])
    np.testing.assert_allclose(chords, 2.0 * np.sin(angles / 2.0), rtol=0, atol=1e-15)  # unit-sphere lengths
    np.testing.assert_allclose(angle_from_chord(chords), angles, rtol=1e-12, atol=1e-15)  # radians
    assert angle_from_chord(2.0 + 1e-12) == math.pi  # a rounded-up chord is the antipode
    for bad in (0.0, -0.1, math.pi + 1e-9, float("nan")):
        with pytest.raises(InvalidInputError, match=r"radius_rad must be in \(0, pi\] radians"):
            chord_from_angle(bad, "radius_rad")


def test_the_tree_cone_query_is_what_the_cone_index_answers():
    vectors = radec_to_vector(np.linspace(0, 6.2, 400), np.linspace(-1.5, 1.5, 400))
    tree, index = cKDTree(vectors), ConeIndex(vectors)
    centre = radec_to_vector(1.0, 0.2)
    assert sorted(query_cone(tree, centre, 0.5)) == index.query(centre, 0.5).tolist()
    many = query_cone(tree, vectors[:3], 0.3)
    assert [list(m) for m in many] == [f.tolist() for f in index.query_many(vectors[:3], 0.3)]
    angles = np.degrees(np.arccos(np.clip(vectors @ centre, -1, 1)))
    assert sorted(query_cone(tree, centre, 0.5)) == np.flatnonzero(angles <= np.degrees(0.5)).tolist()
    with pytest.raises(InvalidInputError, match=r"radius_rad must be in \[0, pi\] radians"):
        query_cone(tree, centre, 4.0)


def test_the_propagate_alias_and_its_import_cycle_are_gone():
    assert "propagate" not in catalog_pkg.__all__
    tree = ast.parse((SRC / "catalog" / "_propagation.py").read_text(encoding="utf-8"))
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert "star_catalog" not in imported  # star_catalog imports propagation, not the other way


# Inline copies of the primitives, and the lines (file: count) that are allowed one with a reason.
COPIES = {
    "epoch": (re.compile(r"\.tdb\.jyear"), {"catalog/_epoch.py": 1}),
    "chord": (re.compile(r"2(\.0)? \* (math|np)\.sin\((0\.5 \* )?[^)]*(/ 2(\.0)?)?\)(?! \*\*)"), {
        "catalog/_chord.py": 1,
    }),
    "arc": (re.compile(r"(np\.arcsin|math\.asin)\((np\.minimum\()?(min\(1\.0, )?0\.5 \*"), {
        "catalog/_chord.py": 1,
        "identify/_match_kernel.py": 1,  # a numba kernel: it cannot call a Python helper
    }),
    "cone": (re.compile(r"\.query_ball_point\("), {
        "catalog/_cone.py": 1,
        "identify/_verify.py": 1,  # field_cone takes a cKDTree or the compiled SkyBands (chord from chord_from_angle)
        "identify/_refine.py": 1,  # SkyBands' warm-up call, not a cKDTree
        "rate/_streak_predict.py": 1,  # a ball in pixels, not a cone on the sphere
    }),
}


def _counts(pattern: re.Pattern) -> dict[str, int]:
    found: dict[str, int] = {}
    for path in sorted(SRC.rglob("*.py")):
        if "adcs" in path.parts:  # quaternion half-angles, not chords
            continue
        hits = sum(1 for line in path.read_text(encoding="utf-8").splitlines()
                   if pattern.search(line) and not line.lstrip().startswith(("#", '"""', "``")))
        if hits:
            found[path.relative_to(SRC).as_posix()] = hits
    return found


@pytest.mark.parametrize("primitive", sorted(COPIES))
def test_no_module_keeps_its_own_copy_of_a_primitive(primitive):
    pattern, allowed = COPIES[primitive]
    found = _counts(pattern)
    extra = {k: v for k, v in found.items() if v > allowed.get(k, 0)}
    assert not extra, f"use the one home of the {primitive} primitive instead: {extra}"


@pytest.mark.parametrize(("primitive", "line"), [
    ("epoch", "return float(epoch.tdb.jyear)"),
    ("chord", "chord = 2.0 * math.sin(min(radius_rad, math.pi) / 2.0)"),
    ("chord", "chord = 2.0 * np.sin(0.5 * max_angle_rad)"),
    ("arc", "np.minimum.at(angle, pairs.max(axis=1), 2.0 * np.arcsin(0.5 * chord))"),
    ("cone", "found = tree.query_ball_point(centres, chord)"),
])
def test_the_copy_finder_sees_the_copies_it_replaced(primitive, line):
    assert COPIES[primitive][0].search(line)
    assert not COPIES["chord"][0].search("t = 2.0 * math.sin(0.5 * angle) ** 2")  # 1 - cos, not a chord


def test_the_epoch_home_loads_neither_numpy_nor_astropy():
    code = ("import sys\nfrom startrack.identify import epoch_jyear\n"
            "print(epoch_jyear(2025.5), 'numpy' in sys.modules, 'astropy.time' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert done.stdout.split() == ["2025.5", "False", "False"]
