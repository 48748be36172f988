"""The campaign spec: what is accepted, what is refused (naming the key), and the cells."""

from __future__ import annotations

import math

import numpy as np
import pytest

from startrack.analysis.campaign._attitudes import fibonacci_radec, trial_attitude
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.frames import boresight

GOOD = """
[campaign]
name = "fov-noise"
level = "stars"
trials = 200
seed = 12345
[base]
fov_deg = 15.0
width = 1024
height = 1024
max_mag = 6.0
centroid_sigma_px = 0.2
drop_fraction = 0.0
false_stars = 0
mag_sigma = 0.1
fov_known = true
[sweep]
fov_deg = [10.0, 20.0]
centroid_sigma_px = [0.1, 0.5]
"""


def test_the_issue_example_parses_into_the_product_of_the_sweep():
    spec = parse_spec(GOOD)
    cells = spec.cells()
    assert [c.label for c in cells] == ["fov_deg=10, centroid_sigma_px=0.1", "fov_deg=10, centroid_sigma_px=0.5",
                                        "fov_deg=20, centroid_sigma_px=0.1", "fov_deg=20, centroid_sigma_px=0.5"]
    assert [c.index for c in cells] == [0, 1, 2, 3]
    assert cells[3].params["fov_deg"] == 20.0 and cells[3].params["centroid_sigma_px"] == 0.5
    assert cells[0].params["mag_sigma"] == 0.1          # from [base]
    assert cells[0].params["max_stars"] == 40           # a default
    assert spec.swept == ["fov_deg", "centroid_sigma_px"]


def test_as_dict_round_trips_through_json_for_the_manifest():
    spec = parse_spec(GOOD)
    assert spec.as_dict()["sweep"] == {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1, 0.5]}
    assert parse_spec(GOOD).as_dict() == spec.as_dict()


def _with(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new)


@pytest.mark.parametrize(("old", "new", "words"), [
    ("fov_deg = 15.0", "fov_deg = \"wide\"", ["[base] fov_deg", "must be a number"]),
    ("fov_deg = 15.0", "fov_deg = 400.0", ["[base] fov_deg", "[0.5, 150]"]),
    ("false_stars = 0", "false_stars = 1.5", ["[base] false_stars", "whole number"]),
    ("fov_known = true", "fov_known = 1", ["[base] fov_known", "true or false"]),
    ("mag_sigma = 0.1", "mag_sigmaa = 0.1", ["[base] mag_sigmaa", "unknown parameter", "mag_sigma"]),
    ("trials = 200", "trials = 0", ["[campaign] trials", "whole number in [1"]),
    ("trials = 200", "trials = 200\nworkers = 3", ["[campaign] workers", "unknown key"]),
    ("level = \"stars\"", "level = \"galaxies\"", ["[campaign] level", "'galaxies'", "image", "stars"]),
    ("name = \"fov-noise\"", "name = \"fov noise!\"", ["[campaign] name"]),
    ("centroid_sigma_px = [0.1, 0.5]", "centroid_sigma_px = 0.1", ["[sweep] centroid_sigma_px", "list"]),
    ("centroid_sigma_px = [0.1, 0.5]", "centroid_sigma_px = []", ["[sweep] centroid_sigma_px", "non-empty"]),
    ("centroid_sigma_px = [0.1, 0.5]", "centroid_sigma_px = [0.1, -0.5]", ["[sweep] centroid_sigma_px", "[0, 100]"]),
    ("centroid_sigma_px = [0.1, 0.5]", "centroid_sigma_px = [0.1, 0.1]", ["[sweep] centroid_sigma_px", "repeats"]),
    ("centroid_sigma_px = [0.1, 0.5]", "centroid_sigma_px = [0.0, -0.0]", ["[sweep] centroid_sigma_px", "repeats"]),
    ("seed = 12345", "seed = 9223372036854775808", ["[campaign] seed", "whole number in [0"]),  # 2**63
    ("[sweep]", "[sweeps]", ["unknown table [sweeps]", "[sweep]"]),
    ("fov_known = true", "fov_known = true\nfov_range_deg = [30.0, 10.0]", ["fov_range_deg", "lower end"]),
    ("seed = 12345", "seed = 12345\nattitudes = \"random\"", ["[campaign] attitudes", "'fibonacci'"]),
    ("[base]", "[base", ["not valid TOML"]),
])
def test_bad_specs_are_refused_naming_the_key(old, new, words):
    with pytest.raises(SpecError) as info:
        parse_spec(_with(GOOD, old, new))
    message = str(info.value)
    for word in words:
        assert word in message, message


def test_a_missing_name_is_refused():
    with pytest.raises(SpecError, match=r"\[campaign\] name: missing"):
        parse_spec(_with(GOOD, 'name = "fov-noise"\n', ""))


def test_a_sweep_of_too_many_cells_is_refused_before_they_are_made():
    """A sweep of 10^6 cells took minutes before the first trial (found by fuzzing the command)."""
    fovs = ", ".join(f"{5 + 0.01 * i:.2f}" for i in range(400))
    sigmas = ", ".join(f"{0.05 + 0.001 * i:.3f}" for i in range(300))
    big = _with(_with(GOOD, "fov_deg = [10.0, 20.0]", f"fov_deg = [{fovs}]"),
                "centroid_sigma_px = [0.1, 0.5]", f"centroid_sigma_px = [{sigmas}]")
    with pytest.raises(SpecError, match=r"makes 120,000 cells \(400 fov_deg x 300 centroid_sigma_px\), more than"):
        parse_spec(big)
    assert len(parse_spec(_with(GOOD, "fov_deg = [10.0, 20.0]", f"fov_deg = [{fovs}]")).cells()) == 800


def test_image_level_refuses_a_detector_setting_the_detector_refuses():
    text = '[campaign]\nname = "x"\nlevel = "image"\ntrials = 1\n[base]\ndetect_kernel_px = 2\n'
    with pytest.raises(SpecError, match="detector settings.*kernel_px"):
        parse_spec(text)


def test_image_level_names_the_valid_detector_methods():
    """A method name of the detector (a Literal of StarDetector) is checked with the spec, naming the valid ones."""
    text = '[campaign]\nname = "x"\nlevel = "image"\ntrials = 1\n[base]\ndetect_threshold = "guess"\n'
    with pytest.raises(SpecError, match="detect_threshold: must be one of 'ksigma', 'dynamic'"):
        parse_spec(text)


def test_image_level_takes_every_detector_and_noise_setting():
    text = ('[campaign]\nname = "x"\nlevel = "image"\ntrials = 1\n[base]\ndetect_sigma = 4.0\n'
            'noise_shot = false\nread_noise_e = 2.5\nexposure_s = "auto"\n'
            '[sweep]\ndetect_centroid = ["mle", "windowed"]\n')
    cell = parse_spec(text).cells()[0]
    assert cell.params["detect_sigma"] == 4.0 and cell.params["noise_shot"] is False
    assert cell.params["read_noise_e"] == 2.5 and cell.params["exposure_s"] is None
    assert cell.params["detect_centroid"] == "mle"


def test_fibonacci_lattice_spreads_sin_dec_evenly_and_keeps_the_roll_random():
    n = 400
    sin_dec = np.array([math.sin(fibonacci_radec(k, n)[1]) for k in range(n)])
    np.testing.assert_allclose(np.sort(sin_dec), np.linspace(-1 + 1 / n, 1 - 1 / n, n), atol=1e-12)
    rng = np.random.default_rng(1)
    rots = [trial_attitude("fibonacci", k, n, rng) for k in range(n)]
    bores = np.array([boresight(r) for r in rots])
    # every lattice direction is the boresight of its trial: nearest neighbours are all similar
    ra, dec = fibonacci_radec(7, n)
    expected = np.array([math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra), math.sin(dec)])
    np.testing.assert_allclose(bores[7], expected, atol=1e-12)
    gaps = np.sort(bores @ bores.T, axis=1)[:, -2]   # cosine to the nearest other boresight
    assert np.degrees(np.arccos(gaps)).max() < 2.5 * np.degrees(np.arccos(gaps)).min()


def test_the_largest_documented_seed_is_taken():
    """2**63 - 1 was refused: its check went through a float, which rounds it up to 2**63."""
    assert parse_spec(_with(GOOD, "seed = 12345", "seed = 9223372036854775807")).seed == 2**63 - 1
    with pytest.raises(SpecError, match="seed"):
        parse_spec(_with(GOOD, "seed = 12345", "seed = -1"))
