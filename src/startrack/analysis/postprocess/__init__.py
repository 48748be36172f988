"""Post-processing analyses over result sets (Fowler 2013 ch. 8): each
a figure (matplotlib ``Figure``, object API) with the numbers behind it as tables.

>>> from startrack.analysis.postprocess import ANALYSES, records_from_images, run_analysis
>>> images = records_from_images(["night/"], solve_options={"fov_deg": 10.2})    # doctest: +SKIP
>>> result = run_analysis("radial", [images])                                     # doctest: +SKIP
>>> result.write("out/radial")             # radial.png, radial_stars.csv, radial_fit.csv  # doctest: +SKIP

Modules: :mod:`.core` (the types, parameter checks), :mod:`.registry` (names, ``run_analysis``),
:mod:`.records_io` (records from image files), :mod:`.spots` (per-spot tables), :mod:`.ground`
(sites, truth, error components), :mod:`.figures` (drawing helpers), :mod:`.rerun` (detection
run again), and one module per analysis: :mod:`.histograms`, :mod:`.gallery`, :mod:`.radial`,
:mod:`.magnitude`, :mod:`.corrections`, :mod:`.repeatability`, :mod:`.thresholds`,
:mod:`.compare`, :mod:`.sweep`. See ``docs/analysis.md``.
"""

from .core import AnalysisInfo, AnalysisResult, ResultSet, check_params, parse_param
from .records_io import image_paths, record_pixels, records_from_images
from .registry import ANALYSES, get_info, run_analysis

__all__ = ["ANALYSES", "AnalysisInfo", "AnalysisResult", "ResultSet", "check_params", "get_info", "image_paths",
           "parse_param", "record_pixels", "records_from_images", "run_analysis"]
