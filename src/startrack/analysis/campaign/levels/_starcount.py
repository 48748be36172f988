"""Level "starcount": the catalog stars in the field at the trial's attitude (star availability;
Jacobs 1995 §5.1 Fig. 5-1, Huffman 2006 §5.1 Table 5.1).

A field is the camera's image (``shape = "image"``: a camera preset, or a pinhole of
``fov_deg`` x the aspect of ``width`` x ``height``; a star counts when it projects inside the
image through the camera model, as :func:`startrack.analysis._availability.star_counts` counts)
or a cone of full angle ``fov_deg`` about the boresight (``shape = "cone"``). The Hipparcos-2
stars (estimated Johnson V, at ``epoch_jyear``) are counted to ``max_mag`` (``n_stars``), and
the field's ``min_stars``-th brightest star to ``catalog_max_mag`` gives the limit this
pointing needs to hold ``min_stars`` stars (``mag_needed_v``; inf when not even
``catalog_max_mag`` suffices). Over a Fibonacci lattice of boresights (``attitudes =
"fibonacci"``), ``max:mag_needed_v`` is the Huffman 2006 Table 5.1 limit "at least n stars in
every field"; over uniform attitudes, ``rate:too_few`` is the share of pointings with fewer
than ``min_stars`` stars to ``max_mag``.

Common columns (no identification): ``status`` "OK"; ``correct`` = the field holds at least
``min_stars`` stars to ``max_mag``; ``n_matched`` 0; ``time_s`` the count's time. Extra
columns: ``mag_needed_v``, ``too_few`` (not ``correct``), and ``exactly_0`` ... ``exactly_4``
(the field holds exactly k stars to ``max_mag``: the low end of the Fig. 5-1 histogram, where
availability fails).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ....camera import PRESETS, Camera, get_preset
from ....catalog import load_catalog, query_cone
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS
from ._measure import measurement_columns

EXACT_COUNTS = range(5)
"""The counts k with a column ``exactly_k``."""

COUNT_PARAMS = (
    Param("camera", "str", "", 'a camera preset ("": a pinhole camera from fov_deg, width, height)',
          choices=("", *sorted(PRESETS))),
    Param("shape", "str", "image", "the field: the camera's image, or a cone of full angle fov_deg",
          choices=("image", "cone")),
    Param("max_mag", "float", 6.0, "faintest star counted in n_stars (V)", lo=-2.0, hi=12.0),
    Param("min_stars", "int", 3, "the stars a field must hold (correct, too_few, mag_needed_v)", lo=1, hi=1000),
    Param("catalog_max_mag", "float", 7.0, "faintest star considered for mag_needed_v (V)", lo=-2.0, hi=12.0),
    Param("epoch_jyear", "float", 2000.0, "epoch of the star positions (Julian year, TDB)", lo=1900.0, hi=2100.0),
)

PARAMS = params_by_name(CAMERA_PARAMS, COUNT_PARAMS)


@dataclass(frozen=True)
class Sky:
    """Catalog stars to a limit, brightest first, with a k-d tree of their directions."""

    vectors: NDArray[np.float64]
    mags: NDArray[np.float64]
    tree: cKDTree


@functools.lru_cache(maxsize=8)
def load_sky(max_mag: float, epoch_jyear: float) -> Sky:
    """The Hipparcos-2 stars with V <= ``max_mag`` at ``epoch_jyear``, sorted by magnitude
    (kept per process)."""
    catalog = load_catalog().brighter_than(max_mag)
    order = np.argsort(np.asarray(catalog.v_mag, dtype=float), kind="stable")
    vectors = catalog.vectors(epoch_jyear)[order]
    return Sky(vectors, np.asarray(catalog.v_mag, dtype=float)[order], cKDTree(vectors))


@functools.lru_cache(maxsize=32)
def field_camera(camera: str, width: int, height: int, fov_deg: float) -> Camera:
    """The camera preset, or a pinhole of ``fov_deg`` across ``width`` x ``height``."""
    return get_preset(camera) if camera else Camera.from_fov(width, height, fov_deg, name="pinhole")


def field_mags(sky: Sky, rot: Rotation, camera: Camera, shape: str, fov_deg: float) -> NDArray[np.float64]:
    """Magnitudes (brightest first) of the stars of ``sky`` in the field at ``rot``
    (``rot_cam_from_icrs``)."""
    matrix = rot.as_matrix()  # rows: the camera axes in ICRS
    if shape == "cone":
        half = math.radians(fov_deg) / 2.0
        idx = query_cone(sky.tree, matrix[2], half)
        return sky.mags[np.sort(np.asarray(idx, dtype=np.intp))]
    reach = min(math.radians(camera.fov_diagonal_deg) / 2.0 * 1.02, math.pi / 2)
    idx = np.sort(np.asarray(query_cone(sky.tree, matrix[2], reach), dtype=np.intp))
    x, y = camera.vector_to_pixel(sky.vectors[idx] @ matrix.T)
    return sky.mags[idx[camera.in_image(x, y)]]


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Count the stars in the field at ``rot``; ``rng`` and ``tolerance_px`` are not used."""
    t0 = time.perf_counter()
    sky = load_sky(params["catalog_max_mag"], params["epoch_jyear"])
    camera = field_camera(params["camera"], params["width"], params["height"], params["fov_deg"])
    mags = field_mags(sky, rot, camera, params["shape"], params["fov_deg"])
    n_stars = int(np.searchsorted(mags, params["max_mag"], side="right"))
    k = params["min_stars"]
    enough = n_stars >= k
    row = measurement_columns(status="OK", correct=enough, n_stars=n_stars, n_matched=0,
                              time_s=time.perf_counter() - t0, rot_cam_from_icrs=rot)
    row.update(mag_needed_v=float(mags[k - 1]) if mags.size >= k else math.inf, too_few=not enough)
    row.update({f"exactly_{n}": n_stars == n for n in EXACT_COUNTS})
    return TrialOutput(row)


def check(params: Mapping[str, Any]) -> None:
    """Refuse a count limit fainter than the catalog loaded, and a camera the preset overrides
    given with the cone shape."""
    if params["max_mag"] > params["catalog_max_mag"]:
        raise SpecError(f"max_mag ({params['max_mag']:g}) must not exceed catalog_max_mag "
                        f"({params['catalog_max_mag']:g}): stars fainter than the catalog loaded are not counted")
    if params["shape"] == "cone" and params["camera"]:
        raise SpecError(f"shape = \"cone\" is a cone of fov_deg; leave camera empty (got {params['camera']!r})")


LEVEL = register(Level(
    name="starcount", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"mag_needed_v": pa.float64(), "too_few": pa.bool_(),
             **{f"exactly_{n}": pa.bool_() for n in EXACT_COUNTS}},
    chunk_trials=2000))
