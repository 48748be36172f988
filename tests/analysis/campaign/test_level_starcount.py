"""Level "starcount" against independent counts, and its specs (Huffman 2006 Table 5.1, Jacobs 1995
Fig. 5-1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis._availability import star_counts
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign.levels import get_level
from startrack.camera import get_preset
from startrack.catalog import load_catalog
from startrack.frames import angle_between, boresight, random_rotations

LEVEL = get_level("starcount")


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_counts_in_the_image_are_those_of_the_availability_study():
    """The same pointings counted by startrack.analysis._availability (batched, its own k-d tree
    and projection chunking) give the same numbers."""
    epoch = float(load_catalog().epoch_jyear)  # availability counts at the catalog's epoch
    expected = star_counts(get_preset("sunsat"), 6.0, 40, rng=7).counts
    rots = random_rotations(40, np.random.default_rng(7))
    p = params(camera="sunsat", max_mag=6.0, epoch_jyear=epoch)
    got = [LEVEL.run(p, rots[i], np.random.default_rng(0), 5.0).row["n_stars"] for i in range(40)]
    assert got == expected.tolist()


def test_cone_limit_is_the_nth_brightest_star_within_half_the_fov():
    catalog = load_catalog().brighter_than(7.0)
    vectors, mags = catalog.vectors(2000.0), np.asarray(catalog.v_mag, dtype=float)
    rots = random_rotations(10, np.random.default_rng(3))
    for i in range(10):
        p = params(shape="cone", fov_deg=20.0, min_stars=5, max_mag=5.0)
        row = LEVEL.run(p, rots[i], np.random.default_rng(0), 5.0).row
        inside = angle_between(vectors, boresight(rots[i])) <= math.radians(10.0)
        field = np.sort(mags[inside])
        assert row["mag_needed_v"] == pytest.approx(field[4], abs=1e-12)
        assert row["n_stars"] == int(np.count_nonzero(field <= 5.0))
        assert row["too_few"] == (row["n_stars"] < 5) and row["correct"] == (not row["too_few"])
        assert sum(row[f"exactly_{k}"] for k in range(5)) == (row["n_stars"] < 5)
        assert row["status"] == "OK" and math.isnan(row["err_total_arcsec"])


def test_a_field_with_too_few_stars_needs_an_infinite_limit():
    rot = random_rotations(None, np.random.default_rng(1))
    row = LEVEL.run(params(shape="cone", fov_deg=1.0, min_stars=50, catalog_max_mag=3.0, max_mag=3.0), rot,
                    np.random.default_rng(0), 5.0).row
    assert row["mag_needed_v"] == math.inf and row["too_few"] and not row["correct"]


@pytest.mark.parametrize(("base", "message"), [
    ('max_mag = 8.0\ncatalog_max_mag = 7.0', "must not exceed catalog_max_mag"),
    ('shape = "cone"\ncamera = "sunsat"', "leave camera empty"),
])
def test_bad_combinations_are_refused_naming_the_keys(base, message):
    with pytest.raises(SpecError, match=message):
        parse_spec(f'[campaign]\nname = "x"\nlevel = "starcount"\n[base]\n{base}\n')


TABLE_51 = {25.0: (3.9, 4.3), 30.0: (3.6, 3.9), 35.0: (3.4, 3.6), 40.0: (3.3, 3.4), 45.0: (3.1, 3.3)}
FIG_51 = {0: 0.021e-3, 1: 1.05e-3, 2: 4.53e-3, 3: 15.46e-3, 4: 35.13e-3}


def test_table51_spec_holds_the_seed_numbers_on_a_1_deg_lattice():
    spec = shipped("huffman2006-table5.1-star-availability")
    assert spec.attitudes == "fibonacci" and spec.trials == 41253  # 4 pi sr / (1 deg)^2
    assert spec.sweep == {"shape": ("cone", "image"), "fov_deg": tuple(TABLE_51), "min_stars": (4, 6)}
    for title in ("Huffman 2006 Table 5.1: V limit for at least n stars in every field (cone",
                  "Huffman 2006 Table 5.1: V limit for at least n stars in every field (square"):
        seeds = seed_numbers(spec, title)
        assert len(seeds) == 10
        for (fov, n, _), value in ((tuple(v for _, v in k), s) for k, s in seeds.items()):
            assert value == TABLE_51[fov][(4, 6).index(n)]


def test_fig51_spec_holds_the_seed_probabilities():
    spec = shipped("jacobs1995-fig5-1-stars-per-fov")
    assert spec.base["camera"] == "sunsat" and spec.sweep == {"max_mag": (6.0, 5.9)}
    for k, p in FIG_51.items():
        seeds = seed_numbers(spec, f"Jacobs 1995 Fig. 5-1: probability of exactly {k} ")
        assert list(seeds.values()) == [pytest.approx(p, rel=1e-12)] * 2
    assert set(seed_numbers(spec, "Jacobs 1995 Fig. 5-1: probability of fewer than 3").values()) == {0.0056}
    assert set(seed_numbers(spec, "Jacobs 1995 Fig. 5-1: most stars").values()) == {49}


@pytest.mark.parametrize("name", ["huffman2006-table5.1-star-availability", "jacobs1995-fig5-1-stars-per-fov"])
def test_tiny_runs_give_every_reference_a_number(name, tmp_path):
    trials, tables = tiny_run(name, tmp_path, trials=3)
    assert set(trials["status"].to_pylist()) == {"OK"}
    assert all(finite(rows) for rows in tables.values())
