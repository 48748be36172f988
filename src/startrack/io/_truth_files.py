"""Writing simulated frames with their truth: FITS (truth as header cards and tables) or PNG/TIFF
with a JSON sidecar; and the index of a sequence.

The truth of a frame (:func:`truth_to_dict`) is its attitude at the frame's mid time (RA / Dec /
roll of the boresight and the quaternion ``qx, qy, qz, qw`` of ``rot_cam_from_icrs``), the time
tag, the camera rate, the catalog epoch, the camera and the sensor, and the stars whose true
position lies in the image: HIP number, x, y (our 0-based pixel convention, at mid-exposure),
the streak's end points ``x_start, y_start, x_end, y_end`` (exposure start and end), magnitude,
colour, expected electrons; then the satellites and the Sun / Moon / Earth flags when the scene
has them.

FITS cards (8 characters at most): TRUE_RA, TRUE_DEC, TRUEROLL (deg), TRUE_QX .. TRUE_QW,
CATEPOCH (Julian year), EXPTIME (s), RATE_X, RATE_Y, RATE_Z (deg/s, camera frame), LINETIME (s),
TMID_S (s on the attitude profile's clock), DATE-OBS / DATE-AVG and MJD-OBS / MJD-AVG (UTC start
and mid, when known),
FRAME; the camera FOCALPX, FOCALPY, CX0, CY0 (0-based px), K1, K2, K3, P1, P2, CAMERA; the
sensor SENSOR, GAIN (e-/ADU), RDNOISE (e-), DARKCUR (e-/s), BIAS (ADU), FULLWELL (e-), BITDEPTH,
QE, APAREA (m^2), PSFSIGMA (px), NOISE (the terms applied); a TAN WCS of the pinhole camera at the
mid attitude (distortion left out); the stars in a ``TRUTH`` table, the satellites in ``RSOTRUTH``,
both after a header-only ``TRUTHDOC`` extension (astrometry.net takes a table with X and Y columns
in extension 1 for a star list; DS9, astropy and solve-field read these files as images).
"""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Iterable
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
from astropy.io import fits
from astropy.time import TimeDelta

from ..errors import InvalidInputError
from ..frames import radec_roll_from_rotation
from ._atomic import atomic_group, open_output
from ._fitsfile import write_fits
from ._targets import output_target
from ._tiff import tiff_bytes
from ._writers import png_bytes

IMAGE_SUFFIXES = {".fits": "fits", ".fit": "fits", ".fts": "fits", ".png": "png", ".tif": "tiff", ".tiff": "tiff"}
STAR_COLUMNS = ("hip", "x", "y", "mag", "electrons", "x_start", "y_start", "x_end", "y_end", "b_v")
RSO_COLUMNS = ("id", "x", "y", "x_start", "y_start", "x_end", "y_end", "mag", "electrons", "range_km", "lit",
               "rendered")
TRUTH_NOTE_EXTNAME = "TRUTHDOC"
"""EXTNAME of the header-only extension that precedes the truth tables in a FITS frame."""
INDEX_COLUMNS = ("frame", "file", "t_mid_s", "time_mid", "ra_deg", "dec_deg", "roll_deg", "qx", "qy", "qz", "qw",
                 "rate_x_deg_s", "rate_y_deg_s", "rate_z_deg_s", "n_stars")


def _num(value) -> float | None:
    """A float for JSON, None for NaN or infinite values."""
    value = float(value)
    return value if math.isfinite(value) else None


def _stars(truth) -> list[dict[str, Any]]:
    inside = truth.inside()
    columns = (truth.ids, truth.x, truth.y, truth.mag, truth.electrons, truth.x_start, truth.y_start,
               truth.x_end, truth.y_end, truth.b_v)
    return [{"hip": int(row[0]), **{k: _num(v) for k, v in zip(STAR_COLUMNS[1:], row[1:], strict=True)}}
            for row in zip(*(c[inside] for c in columns), strict=True)]


def _rsos(rsos) -> list[dict[str, Any]]:
    if rsos is None:
        return []
    columns = [getattr(rsos, name) for name in ("ids", *RSO_COLUMNS[1:])]
    out = []
    for row in zip(*columns, strict=True):
        item: dict[str, Any] = {"id": int(row[0])}
        item.update({k: _num(v) for k, v in zip(RSO_COLUMNS[1:-2], row[1:-2], strict=True)})
        item.update({"lit": bool(row[-2]), "rendered": bool(row[-1])})
        out.append(item)
    return out


def _sensor(truth) -> dict[str, Any]:
    sensor, det, optics = truth.sensor, truth.sensor.detector, truth.sensor.optics
    return {"name": sensor.name, "gain_e_per_adu": det.gain_e_per_adu, "read_noise_e": det.read_noise_e,
            "dark_current_e_s": det.dark_current_e_s, "bias_adu": det.bias_adu, "full_well_e": det.full_well_e,
            "bit_depth": int(det.bit_depth), "quantum_efficiency": det.quantum_efficiency,
            "aperture_area_m2": optics.aperture_area_m2, "transmission": optics.transmission,
            "psf": optics.psf, "psf_sigma_px": optics.psf_sigma_px,
            "passband": None if sensor.passband is None else sensor.passband.name,
            "noise": [f.name for f in fields(truth.noise) if getattr(truth.noise, f.name)]}


def truth_to_dict(truth) -> dict[str, Any]:
    """A JSON-ready dictionary of a :class:`startrack.simulate.Truth` (stars inside the image)."""
    from ..simulate import Truth

    if not isinstance(truth, Truth):
        raise InvalidInputError(f"truth must be a startrack.simulate.Truth (sim.truth of a simulated frame), "
                                f"got {type(truth).__name__}")
    ra, dec, roll = (float(np.degrees(a)) for a in radec_roll_from_rotation(truth.rot_cam_from_icrs))
    qx, qy, qz, qw = (float(q) for q in truth.rot_cam_from_icrs.as_quat())
    cam = truth.camera
    epoch = None if truth.epoch_jyear is None else float(truth.epoch_jyear)
    flags = truth.bright_bodies
    return {"ra_deg": ra, "dec_deg": dec, "roll_deg": roll, "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "epoch_jyear": epoch, "exposure_s": float(truth.exposure_s),
            "rate_deg_s": [float(v) for v in np.degrees(truth.rate_cam_rad_s)],
            "t_mid_s": float(truth.t_mid_s),
            "time_mid": None if truth.time_mid is None else truth.time_mid.utc.isot,
            "line_time_s": float(truth.line_time_s), "frame_index": truth.frame_index,
            "camera": {"width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy, "cx": cam.cx,
                       "cy": cam.cy, "k1": cam.k1, "k2": cam.k2, "k3": cam.k3, "p1": cam.p1, "p2": cam.p2,
                       "fov_deg": cam.fov_deg, "name": cam.name},
            "sensor": _sensor(truth),
            "stars": _stars(truth),
            "rsos": _rsos(truth.rsos),
            "bright_bodies": None if flags is None else {f.name: getattr(flags, f.name) for f in fields(flags)}}


def _wcs_cards(truth, data: dict[str, Any]) -> dict[str, Any]:
    """TAN WCS of the pinhole camera at the mid attitude (docs/conventions.md, "FITS WCS")."""
    cam = truth.camera
    r = math.radians(data["roll_deg"])
    deg = 180.0 / math.pi
    return {"CTYPE1": "RA---TAN", "CTYPE2": "DEC--TAN", "CUNIT1": "deg", "CUNIT2": "deg",
            "CRPIX1": cam.cx + 1.0, "CRPIX2": cam.cy + 1.0, "CRVAL1": data["ra_deg"], "CRVAL2": data["dec_deg"],
            "CD1_1": -math.cos(r) * deg / cam.fx, "CD1_2": math.sin(r) * deg / cam.fy,
            "CD2_1": -math.sin(r) * deg / cam.fx, "CD2_2": -math.cos(r) * deg / cam.fy}


def _fits_header(truth, data: dict[str, Any]) -> dict[str, Any]:
    keys = {"TRUE_RA": "ra_deg", "TRUE_DEC": "dec_deg", "TRUEROLL": "roll_deg", "TRUE_QX": "qx",
            "TRUE_QY": "qy", "TRUE_QZ": "qz", "TRUE_QW": "qw", "EXPTIME": "exposure_s", "TMID_S": "t_mid_s",
            "LINETIME": "line_time_s"}
    header = {card: data[key] for card, key in keys.items()}
    header.update(dict(zip(("RATE_X", "RATE_Y", "RATE_Z"), data["rate_deg_s"], strict=True)))
    cam, sen = data["camera"], data["sensor"]
    header.update({"FOCALPX": cam["fx"], "FOCALPY": cam["fy"], "CX0": cam["cx"], "CY0": cam["cy"],
                   **{k.upper(): cam[k] for k in ("k1", "k2", "k3", "p1", "p2")},
                   "CAMERA": cam["name"] or "pinhole", "SENSOR": sen["name"] or "custom",
                   "GAIN": sen["gain_e_per_adu"], "RDNOISE": sen["read_noise_e"], "DARKCUR": sen["dark_current_e_s"],
                   "BIAS": sen["bias_adu"], "FULLWELL": sen["full_well_e"], "BITDEPTH": sen["bit_depth"],
                   "QE": sen["quantum_efficiency"], "APAREA": sen["aperture_area_m2"],
                   "PSFSIGMA": sen["psf_sigma_px"], "NOISE": ",".join(sen["noise"]) or "none"})
    if data["epoch_jyear"] is not None:
        header["CATEPOCH"] = data["epoch_jyear"]
    if truth.time_mid is not None:
        half = TimeDelta(truth.t_mid_s - _start_s(truth), format="sec")
        header["DATE-OBS"] = (truth.time_mid - half).utc.isot
        header["DATE-AVG"] = data["time_mid"]
        header["MJD-OBS"] = float((truth.time_mid - half).utc.mjd)
        header["MJD-AVG"] = float(truth.time_mid.utc.mjd)
    if data["frame_index"] is not None:
        header["FRAME"] = int(data["frame_index"])
    if data["bright_bodies"] is not None:
        header.update({"SUNEDGE": data["bright_bodies"]["sun_edge_deg"],
                       "MOONEDGE": data["bright_bodies"]["moon_edge_deg"],
                       "EARTHEDG": data["bright_bodies"]["earth_edge_deg"]})
    header.update(_wcs_cards(truth, data))
    return header


def _start_s(truth) -> float:
    """Start of the exposure of row 0 on the profile's clock."""
    return truth.t_mid_s - 0.5 * truth.exposure_s - 0.5 * (truth.camera.height - 1) * truth.line_time_s


def _table(rows: list[dict[str, Any]], columns: tuple[str, ...], dtypes: dict[str, Any]) -> dict[str, np.ndarray]:
    return {c: np.array([np.nan if r[c] is None else r[c] for r in rows], dtype=dtypes.get(c, float))
            for c in columns}


def check_frame_path(path: str | os.PathLike, *, inputs: Iterable[str | os.PathLike] = ()) -> str:
    """The kind of file ``path`` names ("fits", "png" or "tiff"), checked before any work is done.

    The image and (for PNG / TIFF) its sidecar must both be writable targets
    (:func:`startrack.io._targets.output_target`) and neither may be one of ``inputs``.

    Raises
    ------
    InvalidInputError
        If the suffix is not .fits / .fit / .fts / .png / .tif / .tiff, the folder does not exist,
        the path or its sidecar is a folder or an input.
    """
    path = Path(path)
    kind = IMAGE_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise InvalidInputError(f"cannot write {str(path)!r}: use a .fits, .png or .tif path")
    for target in frame_paths(path):
        output_target(target, inputs)
    return kind


def frame_paths(path: str | os.PathLike) -> list[Path]:
    """The files :func:`write_frame` writes for ``path``: the image, and a sidecar for PNG / TIFF."""
    path = Path(path)
    if IMAGE_SUFFIXES.get(path.suffix.lower()) == "fits":
        return [path]
    return [path, path.with_name(path.stem + ".truth.json")]


def truth_note_hdu() -> fits.ImageHDU:
    """The header-only extension written first after the image (see :func:`write_frame`)."""
    hdu = fits.ImageHDU(name=TRUTH_NOTE_EXTNAME)
    for text in ("Truth of a frame simulated by startrack: the stars in the TRUTH table,",
                 "satellites in RSOTRUTH; x, y are 0-based pixel centres (add 1 for FITS).",
                 "This header-only extension comes first so that readers that take a",
                 "table with X and Y columns in extension 1 for a star list (astrometry.net's",
                 "solve-field) read the file as the image it is."):
        hdu.header.add_comment(text)
    return hdu


def write_frame(path: str | os.PathLike, image: np.ndarray, truth, *,
                inputs: Iterable[str | os.PathLike] = ()) -> list[Path]:
    """Write an image and its truth; returns the files written.

    ``.fits`` gets the truth as header cards and, after a header-only ``TRUTHDOC`` extension
    (:func:`truth_note_hdu`; it keeps astrometry.net from reading the file as a star list), the
    ``TRUTH`` (+ ``RSOTRUTH``) tables; ``.png`` / ``.tif`` get a ``<stem>.truth.json`` file beside
    them. A float image (e.g. the noise-free expectation) is kept as is in FITS and rounded and
    clipped to 0..65535 uint16 for PNG / TIFF. The image and its sidecar are written as one group
    (:func:`startrack.io._atomic.atomic_group`): both are replaced, or neither.

    Raises
    ------
    InvalidInputError
        For a path :func:`check_frame_path` refuses, or an image the writer refuses.
    OutputError
        If writing fails; the files there before are then unchanged.
    """
    path = Path(path)
    kind = check_frame_path(path, inputs=inputs)
    data = truth_to_dict(truth)
    if kind == "fits":
        tables = {"TRUTH": _table(data["stars"], STAR_COLUMNS, {"hip": np.int64})}
        if data["rsos"]:
            tables["RSOTRUTH"] = _table(data["rsos"], RSO_COLUMNS, {"id": np.int64, "lit": bool, "rendered": bool})
        return [write_fits(path, image, header=_fits_header(truth, data), tables=tables, inputs=inputs,
                           leading=[truth_note_hdu()])]
    if np.asarray(image).dtype.kind == "f":
        image = np.clip(np.round(image), 0, np.iinfo(np.uint16).max).astype(np.uint16)
    blob = png_bytes(image) if kind == "png" else tiff_bytes(np.asarray(image))
    return write_with_sidecar(path, blob, json.dumps(data, indent=1, allow_nan=False), inputs=inputs)


def write_with_sidecar(path: Path, blob: bytes, sidecar_text: str, *,
                       inputs: Iterable[str | os.PathLike] = ()) -> list[Path]:
    """Write an encoded image and its ``<stem>.truth.json`` together: both, or neither."""
    paths = [path, path.with_name(path.stem + ".truth.json")]
    with atomic_group(paths, inputs=inputs) as (image_tmp, sidecar_tmp):
        image_tmp.write_bytes(blob)
        sidecar_tmp.write_text(sidecar_text, encoding="utf-8")
    return paths


def index_row(truth, file: str | os.PathLike) -> dict[str, Any]:
    """One row of a sequence index (:data:`INDEX_COLUMNS`) for a frame written to ``file``."""
    data = truth_to_dict(truth)
    rate = data["rate_deg_s"]
    return {"frame": data["frame_index"], "file": Path(file).name, "t_mid_s": data["t_mid_s"],
            "time_mid": data["time_mid"] or "", **{k: data[k] for k in ("ra_deg", "dec_deg", "roll_deg")},
            **{k: data[k] for k in ("qx", "qy", "qz", "qw")},
            "rate_x_deg_s": rate[0], "rate_y_deg_s": rate[1], "rate_z_deg_s": rate[2],
            "n_stars": len(data["stars"])}


def write_index(path: str | os.PathLike, rows: list[dict[str, Any]]) -> Path:
    """Write a sequence index as CSV (:func:`startrack.io._atomic.open_output`); quaternions scalar
    last, angles in degrees."""
    with open_output(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=INDEX_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return Path(path)
