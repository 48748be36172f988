"""Post-processing analyses over result sets (Fowler 2013 ch. 8): each
a figure (matplotlib ``Figure``, object API) with the numbers behind it as tables.

>>> from startrack.analysis.postprocess import ANALYSES, records_from_images, run_analysis
>>> images = records_from_images(["night/"], solve_options={"fov_deg": 10.2})    # doctest: +SKIP
>>> result = run_analysis("radial", [images])                                     # doctest: +SKIP
>>> result.write("out/radial")             # radial.png, radial_stars.csv, radial_fit.csv  # doctest: +SKIP

Modules: :mod:`._core` (the types, parameter checks), :mod:`._registry` (names, ``run_analysis``),
:mod:`._records_io` (records from image files), :mod:`._spots` (per-spot tables), :mod:`._ground`
(sites, truth, error components), :mod:`._figures` (drawing helpers), :mod:`._rerun` (detection
run again), and one module per analysis: :mod:`._histograms`, :mod:`._gallery`, :mod:`._radial`,
:mod:`._magnitude`, :mod:`._corrections`, :mod:`._repeatability`, :mod:`._thresholds`,
:mod:`._compare`, :mod:`._sweep`. See ``docs/analysis.md``.
"""

from ._core import AnalysisInfo, AnalysisResult, ResultSet, check_params, csv_cell, parse_param
from ._corrections import pinhole
from ._ground import error_arcsec
from ._records_io import UNREADABLE, image_paths, record_pixels, records_from_images, true_rotation_from_file
from ._registry import ANALYSES, get_info, run_analysis

__all__ = ["ANALYSES", "UNREADABLE", "AnalysisInfo", "AnalysisResult", "ResultSet", "check_params", "csv_cell",
           "error_arcsec", "get_info", "image_paths", "parse_param", "pinhole", "record_pixels", "records_from_images",
           "run_analysis", "true_rotation_from_file"]
