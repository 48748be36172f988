"""Writing a simulated frame with its truth: FITS (truth as a table) or PNG/TIFF + JSON sidecar.

The truth of a frame is its attitude (RA / Dec / roll of the boresight and the quaternion
``qx, qy, qz, qw`` of ``rot_cam_from_icrs``), the catalog epoch of the star positions, its camera,
and the stars whose true position lies in the image: HIP number, x, y (our 0-based pixel
convention), magnitude, expected electrons.

FITS header cards: TRUE_RA, TRUE_DEC, TRUEROLL (deg), TRUE_QX .. TRUE_QW, CATEPOCH (Julian year;
absent when unknown), EXPTIME (s), FOCALPX, CAMERA; the stars are in a ``TRUTH`` table. A PNG or
TIFF ``<stem>.png`` gets the JSON of :func:`truth_to_dict` in ``<stem>.truth.json``.
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
    epoch = None if truth.epoch_jyear is None else float(truth.epoch_jyear)
    return {"ra_deg": ra, "dec_deg": dec, "roll_deg": roll, "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "epoch_jyear": epoch, "exposure_s": float(truth.exposure_s),
            "camera": {"width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy, "cx": cam.cx,
                       "cy": cam.cy, "k1": cam.k1, "k2": cam.k2, "k3": cam.k3, "p1": cam.p1, "p2": cam.p2,
                       "fov_deg": cam.fov_deg, "name": cam.name},
            "stars": stars}


def _fits_header(truth: dict[str, Any]) -> dict[str, Any]:
    keys = {"TRUE_RA": "ra_deg", "TRUE_DEC": "dec_deg", "TRUEROLL": "roll_deg", "TRUE_QX": "qx",
            "TRUE_QY": "qy", "TRUE_QZ": "qz", "TRUE_QW": "qw", "EXPTIME": "exposure_s"}
    header = {card: truth[key] for card, key in keys.items()}
    header.update({"FOCALPX": truth["camera"]["fx"], "CAMERA": truth["camera"]["name"] or "pinhole"})
    if truth["epoch_jyear"] is not None:
        header["CATEPOCH"] = truth["epoch_jyear"]
    return header


def check_frame_path(path: str | os.PathLike) -> str:
    """The kind of file ``path`` names ("fits", "png" or "tiff"), checked before any work is done.

    Raises
    ------
    InvalidInputError
        If the suffix is not .fits / .fit / .fts / .png / .tif / .tiff, the folder does not exist,
        or the path is a folder.
    """
    path = Path(path)
    kind = IMAGE_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise InvalidInputError(f"cannot write {str(path)!r}: use a .fits, .png or .tif path")
    if path.is_dir():
        raise InvalidInputError(f"cannot write {path}: it is a folder, give a file name")
    if not path.parent.is_dir():
        raise InvalidInputError(f"cannot write {path}: folder {path.parent} does not exist")
    return kind


def write_frame(path: str | os.PathLike, image: np.ndarray, truth) -> list[Path]:
    """Write an image and its truth; returns the files written.

    ``.fits`` gets the truth as header cards and a ``TRUTH`` table; ``.png`` / ``.tif`` get a
    ``<stem>.truth.json`` file beside them. A float image (e.g. the noise-free expectation) is
    kept as is in FITS and rounded and clipped to 0..65535 uint16 for PNG / TIFF. Each file is
    written atomically, and the image is removed again if its sidecar cannot be written, so an
    error leaves nothing behind.

    Raises
    ------
    InvalidInputError
        For a path :func:`check_frame_path` refuses, or an image the writer refuses.
    """
    path = Path(path)
    kind = check_frame_path(path)
    data = truth_to_dict(truth)
    if kind == "fits":
        stars = data["stars"]
        table = {k: np.array([s[k] for s in stars]) for k in ("hip", "x", "y", "mag", "electrons")}
        return [write_fits(path, image, header=_fits_header(data), tables={"TRUTH": table})]
    sidecar = path.with_name(path.stem + ".truth.json")
    if np.asarray(image).dtype.kind == "f":
        image = np.clip(np.round(image), 0, np.iinfo(np.uint16).max).astype(np.uint16)
    written = (write_png if kind == "png" else write_tiff)(path, image)
    try:
        with atomic_path(sidecar) as tmp:
            tmp.write_text(json.dumps(data, indent=1, allow_nan=False))
    except BaseException:
        written.unlink(missing_ok=True)
        raise
    return [written, sidecar]
