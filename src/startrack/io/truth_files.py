"""Writing a simulated frame with its truth: FITS (truth as a table) or PNG/TIFF + JSON sidecar.

The truth of a frame is its attitude (RA / Dec / roll of the boresight and the quaternion
``qx, qy, qz, qw`` of ``rot_cam_from_icrs``), its camera, and the stars whose true position lies
in the image: HIP number, x, y (our 0-based pixel convention), magnitude, expected electrons.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..frames import radec_roll_from_rotation
from .atomic import atomic_path
from .fitsfile import write_fits
from .writers import write_png, write_tiff

IMAGE_SUFFIXES = {".fits": "fits", ".fit": "fits", ".fts": "fits", ".png": "png", ".tif": "tiff", ".tiff": "tiff"}


def truth_to_dict(truth) -> dict[str, Any]:
    """A JSON-ready dictionary of a :class:`startrack.simulate.Truth` (stars inside the image)."""
    ra, dec, roll = (float(np.degrees(a)) for a in radec_roll_from_rotation(truth.rot_cam_from_icrs))
    qx, qy, qz, qw = (float(q) for q in truth.rot_cam_from_icrs.as_quat())
    cam = truth.camera
    inside = truth.inside()
    stars = [{"hip": int(h), "x": float(x), "y": float(y), "mag": float(m), "electrons": float(e)}
             for h, x, y, m, e in zip(truth.ids[inside], truth.x[inside], truth.y[inside], truth.mag[inside],
                                      truth.electrons[inside], strict=True)]
    return {"ra_deg": ra, "dec_deg": dec, "roll_deg": roll, "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "exposure_s": float(truth.exposure_s),
            "camera": {"width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy, "cx": cam.cx,
                       "cy": cam.cy, "k1": cam.k1, "k2": cam.k2, "k3": cam.k3, "p1": cam.p1, "p2": cam.p2,
                       "fov_deg": cam.fov_deg, "name": cam.name},
            "stars": stars}


def _fits_header(truth: dict[str, Any]) -> dict[str, Any]:
    keys = {"TRUE_RA": "ra_deg", "TRUE_DEC": "dec_deg", "TRUEROLL": "roll_deg", "TRUE_QX": "qx",
            "TRUE_QY": "qy", "TRUE_QZ": "qz", "TRUE_QW": "qw", "EXPTIME": "exposure_s"}
    header = {card: truth[key] for card, key in keys.items()}
    header.update({"FOCALPX": truth["camera"]["fx"], "CAMERA": truth["camera"]["name"] or "pinhole"})
    return header


def write_frame(path: str | os.PathLike, image: np.ndarray, truth) -> list[Path]:
    """Write an image and its truth; returns the files written.

    ``.fits`` gets the truth as header cards and a ``TRUTH`` table; ``.png`` / ``.tif`` get a
    ``<name>.truth.json`` file beside them.
    """
    path = Path(path)
    kind = IMAGE_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise InvalidInputError(f"cannot write {path.name}: use a .fits, .png or .tif path")
    data = truth_to_dict(truth)
    if kind == "fits":
        stars = data["stars"]
        table = {k: np.array([s[k] for s in stars]) for k in ("hip", "x", "y", "mag", "electrons")}
        return [write_fits(path, image, header=_fits_header(data), tables={"TRUTH": table})]
    written = [(write_png if kind == "png" else write_tiff)(path, image)]
    sidecar = path.with_name(path.stem + ".truth.json")
    with atomic_path(sidecar) as tmp:
        tmp.write_text(json.dumps(data, indent=1))
    return [*written, sidecar]
