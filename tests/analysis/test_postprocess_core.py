"""startrack.analysis.postprocess: the registry, the parameter checks and every refusal, the CSV /
PNG writing, and result sets from image files (simulated frames written as `startrack simulate`
writes them, a corrupt file, the real images of ../shared/realdata)."""

from __future__ import annotations

import csv
import math
from dataclasses import FrozenInstanceError, replace

import numpy as np
import pytest
from matplotlib.figure import Figure

from startrack import Camera
from startrack.analysis._records import ImageRecord
from startrack.analysis.postprocess import (
    ANALYSES,
    AnalysisResult,
    ResultSet,
    check_params,
    image_paths,
    parse_param,
    record_pixels,
    records_from_images,
    run_analysis,
)
from startrack.analysis.postprocess import _records_io as records_io
from startrack.analysis.postprocess._core import PARAM_TYPES
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error, random_rotations
from startrack.io._truth_files import write_frame
from startrack.results import AttitudeSolution, Status
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC

NAMES = ("histograms", "gallery", "radial", "magnitude", "corrections", "repeatability", "thresholds", "compare",
         "sweep")
CAMERA = Camera.from_fov(384, 320, 12.0)
FOV_DEG = 12.0


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    """Two simulated frames, one FITS (truth in its header) and one PNG (truth in a sidecar), and a
    file with a .png name that is not an image, in one folder; with their true attitudes."""
    folder = tmp_path_factory.mktemp("frames")
    truths = random_rotations(2, rng=5)
    sensor = get_sensor_preset("generic-cmos")
    for i, name in enumerate(("a.fits", "b.png")):
        sim = simulate_frame(CAMERA, truths[i], max_mag=7.0, sensor=sensor, rng=i)
        write_frame(folder / name, sim.image, sim.truth)
    (folder / "c.png").write_bytes(b"not an image at all")
    (folder / "notes.txt").write_text("not looked at")
    return folder, {"a.fits": truths[0], "b.png": truths[1]}


@pytest.fixture(scope="module")
def image_set(frames):
    calls = []
    result = records_from_images(frames[0], solve_options={"fov_deg": FOV_DEG, "sigma": 5.0},
                                 progress=lambda done, total: calls.append((done, total)))
    return result, calls


def _sets(image_set):
    return [ResultSet("sim", tuple(r for r in image_set[0].records if r.solution.solved))]


def test_the_nine_analyses_are_registered_in_the_seeds_order_with_checked_declarations():
    assert tuple(ANALYSES) == NAMES
    for name, info in ANALYSES.items():
        assert info.name == name and info.title and info.description
        assert 1 <= info.min_sets <= info.max_sets
        assert all(kind in PARAM_TYPES for kind, _, _ in info.params.values())
        assert set(check_params(info, None)) == set(info.params)  # every default passes its own check
        with pytest.raises(FrozenInstanceError):
            info.name = "x"
    assert [n for n, i in ANALYSES.items() if i.needs_images] == ["gallery", "thresholds", "sweep"]


def test_records_from_a_folder_solve_each_image_and_keep_a_failed_record_for_a_bad_file(frames, image_set):
    result, calls = image_set
    assert result.name == frames[0].name
    assert [r.name for r in result.records] == ["a.fits", "b.png", "c.png"]  # notes.txt is not an image name
    assert calls == [(1, 3), (2, 3), (3, 3)]
    bad = result.records[2]
    assert bad.solution.status is Status.TOO_FEW_STARS and bad.solution.reason.startswith("unreadable image:")
    assert bad.image is None and bad.path == frames[0] / "c.png"
    for record in result.records[:2]:
        assert record.solution.solved, record.solution.reason
        truth = frames[1][record.name]
        # the truth read back from the FITS cards and from the JSON sidecar
        assert attitude_error(truth, record.true_rot_cam_from_icrs) < 1e-6 * ARCSEC
        assert attitude_error(truth, record.solution.rot_cam_from_icrs) < 2 * CAMERA.pixel_scale_arcsec * ARCSEC
        assert record.settings["fov_deg"] == FOV_DEG and record.settings["detector"] == {}  # sigma 5 is the default
        assert record.image.shape == (CAMERA.height, CAMERA.width) and record.path.parent == frames[0]


def test_records_keep_only_the_path_beyond_the_pixel_budget_and_read_the_pixels_again(frames, image_set,
                                                                                     monkeypatch):
    monkeypatch.setattr(records_io, "KEEP_PIXELS_MAX", CAMERA.width * CAMERA.height)
    lean = records_from_images([frames[0] / "a.fits", frames[0] / "b.png"], solve_options={"fov_deg": FOV_DEG})
    assert lean.records[0].image is not None and lean.records[1].image is None
    assert np.array_equal(record_pixels(lean.records[1]), image_set[0].records[1].image)
    with pytest.raises(InvalidInputError, match="no image and no path"):
        record_pixels(replace(lean.records[1], path=None))


@pytest.mark.parametrize(("options", "words"), [
    ({"fov_deg": 200.0}, "fov_deg"),
    ({"fov_range_deg": (20.0, 10.0)}, "low <= high"),
    ({"camera": "no-such-camera"}, "valid presets"),
    ({"site": "atlantis"}, "known sites"),
    ({"thresholds": 3}, "unknown solve option 'thresholds'"),
    ({"detector": {"sigmaa": 3}}, "unknown detector setting 'sigmaa'"),
    ({"sigma": -1.0}, "sigma"),
])
def test_bad_solve_options_are_refused_before_any_file_is_read(frames, options, words):
    with pytest.raises(InvalidInputError, match=words):
        records_from_images(frames[0] / "does-not-matter.fits", solve_options=options)


def test_image_paths_refuse_a_missing_path_and_a_folder_without_images(tmp_path):
    with pytest.raises(InvalidInputError, match="no such file or folder"):
        image_paths(tmp_path / "nope")
    with pytest.raises(InvalidInputError, match="holds no image files"):
        image_paths(tmp_path)
    with pytest.raises(InvalidInputError, match="at least one"):
        image_paths([])


def test_unknown_analysis_wrong_set_counts_and_empty_sets_are_refused(image_set):
    sets = _sets(image_set)
    with pytest.raises(InvalidInputError, match="unknown analysis 'nope'; valid analyses: histograms, gallery"):
        run_analysis("nope", sets)
    with pytest.raises(InvalidInputError, match="compare takes exactly 2 result set"):
        run_analysis("compare", sets)
    with pytest.raises(InvalidInputError, match="repeatability takes exactly 1"):
        run_analysis("repeatability", sets * 2)
    with pytest.raises(InvalidInputError, match="histograms takes 1 to 6"):
        run_analysis("histograms", sets * 7)
    with pytest.raises(InvalidInputError, match="has no images"):
        run_analysis("radial", [ResultSet("empty", ())])
    with pytest.raises(InvalidInputError, match="ImageRecord"):
        ResultSet("x", ("not a record",))
    with pytest.raises(InvalidInputError, match="non-empty name"):
        ResultSet("", ())


@pytest.mark.parametrize(("name", "params", "words"), [
    ("histograms", {"binz": 3}, "unknown parameter 'binz'; valid parameters: bins, image_bins, image"),
    ("radial", {"bins": 3}, "valid parameters: none"),
    ("histograms", {"bins": "30"}, "'bins' must be a whole number"),
    ("histograms", {"bins": True}, "'bins' must be a whole number"),
    ("histograms", {"bins": 2.5}, "'bins' must be a whole number"),
    ("histograms", {"bins": 1}, "'bins' must have a value within 2..500"),
    ("histograms", {"image": 1}, "'image' must be true or false"),
    ("gallery", {"stamp_px": 14}, "'stamp_px' must be odd"),
    ("gallery", {"seed": -1}, "'seed' must have a value within 0..inf"),
    ("corrections", {"latitude_deg": float("nan")}, "finite"),
    ("corrections", {"latitude_deg": 95.0}, "'latitude_deg' must have a value within -90..90"),
    ("corrections", {"latitude_deg": 40.0}, "give both 'latitude_deg' and 'longitude_deg'"),
    ("corrections", {"camera": "nope"}, "valid presets"),
    ("thresholds", {"sigmas": 4.0}, "'sigmas' must be a list"),
    ("thresholds", {"sigmas": []}, "'sigmas' must have a length within 1..20"),
    ("thresholds", {"sigmas": [4.0, "x"]}, "'sigmas' must hold numbers"),
    ("thresholds", {"sigmas": [[4.0]]}, "list of numbers or strings"),
    ("sweep", {"setting": "colour"}, "'setting' must be one of"),
    ("sweep", {"setting": "min_area_px", "values": [2, 2]}, "holds a value twice"),
    ("sweep", {"setting": "sigma", "values": [4, 4.0]}, "holds a value twice"),  # both run as sigma=4.0
    ("histograms", [1], "the parameters must be a mapping"),
    ("sweep", {"setting": "min_area_px", "values": [2, 0]}, "parameter 'values': min_area_px=0 is refused"),
    ("sweep", {"setting": "centroid", "values": ["windowed", "magic"]}, "centroid='magic' is refused"),
])
def test_bad_parameters_are_refused_naming_the_parameter(image_set, name, params, words):
    with pytest.raises(InvalidInputError, match=words.replace("(", r"\(").replace(".", r"\.")):
        run_analysis(name, _sets(image_set), params)


def test_analyses_that_read_pixels_refuse_records_without_them(image_set):
    record = replace(image_set[0].records[0], image=None, path=None)
    with pytest.raises(InvalidInputError, match="gallery needs the images' pixels; record 'a.fits'"):
        run_analysis("gallery", [ResultSet("bare", (record,))])


def test_parse_param_reads_numbers_booleans_and_lists_for_the_declared_type():
    info = ANALYSES["sweep"]
    assert parse_param(info, "values", "3,4.5, 6") == [3, 4.5, 6]
    assert parse_param(info, "values", "[3, 4.5]") == [3, 4.5]
    assert parse_param(info, "values", "windowed,mle") == ["windowed", "mle"]
    assert parse_param(info, "setting", " sigma ") == "sigma"
    assert parse_param(ANALYSES["histograms"], "image", "false") is False
    assert parse_param(ANALYSES["corrections"], "latitude_deg", "41") == 41.0
    assert isinstance(parse_param(ANALYSES["corrections"], "latitude_deg", "41"), float)
    with pytest.raises(InvalidInputError, match="not a JSON list"):
        parse_param(info, "values", "[3, 4")
    with pytest.raises(InvalidInputError, match="unknown parameter 'x'"):
        parse_param(info, "x", "1")


def test_write_puts_the_figure_and_each_table_in_the_folder_and_the_csv_reads_back(tmp_path):
    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    tables = {"t": {"name": ["a", "b"], "value": [1.25, math.nan], "flag": [True, False], "n": [3, None]}}
    result = AnalysisResult("demo", "Demo", fig, tables, {"n": 2})
    written = result.write(tmp_path / "new" / "folder")
    assert [p.name for p in written] == ["demo.png", "demo_t.csv"]
    assert written[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(written[1], newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows == [["name", "value", "flag", "n"], ["a", "1.25", "true", "3"], ["b", "", "false", ""]]
    assert sorted(p.name for p in written[0].parent.iterdir()) == ["demo.png", "demo_t.csv"]  # no temporary left
    with pytest.raises(ValueError, match="lengths"):
        AnalysisResult("bad", "Bad", fig, {"t": {"a": [1, 2], "b": [1]}}, {})


def test_real_images_make_a_result_set(realdata_dir):
    folder = realdata_dir / "smroid-cedar-solve"
    result = records_from_images([folder / "roof.jpg", folder / "pleiades.jpg"], solve_options={"fov_deg": 10.2},
                                 name="cedar")
    assert result.name == "cedar"
    assert all(r.solution.solved for r in result.records), [r.solution.reason for r in result.records]
    assert all(r.true_rot_cam_from_icrs is None and r.time is None for r in result.records)
    histograms = run_analysis("histograms", [result])
    assert histograms.summary["cedar: images"] == 2
    assert sum(histograms.tables["image_histogram"]["count"]) == sum(r.image.size for r in result.records)


def test_a_failed_record_takes_part_as_unsolved(image_set):
    records = image_set[0].records
    result = run_analysis("histograms", [ResultSet("all", records)], {"image": False})
    counts = result.tables["counts"]
    assert counts["solved"] == [True, True, False] and counts["n_detected"][2] == 0
    assert "image_histogram" not in result.tables
    rerun = run_analysis("thresholds", [ResultSet("all", records)], {"sigmas": [6.0]}).tables["images"]
    assert rerun["record"] == ["a.fits", "b.png"]  # nothing to detect again in the unreadable file
    bare = ImageRecord("x", AttitudeSolution(status=Status.NO_MATCH, reason="no pattern"))
    assert run_analysis("radial", [ResultSet("none", (bare,))]).summary["none: stars"] == 0
