"""FITS WCS export: the TAN (gnomonic) projection with SIP distortion for any solved image.

A camera looking along ``rot_cam_from_icrs`` is exactly a TAN projection about its optical axis
until the lens distorts it, so (FITS WCS Paper II; Shupe et al. 2005 for SIP):

- ``CRPIX`` = the principal point (cx, cy) **plus 1** (FITS pixel centres are 1-based; see
  :mod:`startrack.conventions`), ``CRVAL`` = RA, Dec of the optical axis;
- ``CD`` maps the *undistorted* pixel offsets (u', v') = (fx a, fy b), with (a, b) the pinhole
  coordinates, to the standard coordinates (xi east, eta north) in degrees: its columns are the
  camera's x and y axes at the tangent point, projected on east and north, divided by fx and fy
  (-fx for a ``mirrored`` camera, whose pixel x runs against its x axis: the sign of the CD's
  determinant, positive for a camera's own image with row 0 at the top, is then negative);
- SIP ``A, B`` give ``u' - u`` as polynomials in the measured offsets (u, v) = pixel - CRPIX
  (lens undistortion), and ``AP, BP`` the inverse ``u - u'`` (the distortion). The Brown-Conrady
  distortion is a polynomial in (a, b) of degree 7 at most, so AP/BP reproduce it exactly at
  order 7 (3 for k1 only with no k2, k3); A/B approximate its inverse, and the order is the lowest
  (2..13) that reproduces the camera to ``max_residual_px`` over the image.

Astropy reads the result (``astropy.wcs.WCS``; its high-level ``pixel_to_world`` takes our 0-based
pixels unchanged), and so do ds9, astrometry.net and SIP-aware tools.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from astropy.io import fits
from astropy.time import Time
from astropy.wcs import WCS
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..conventions import FITS_PIXEL_OFFSET
from ..errors import InvalidInputError
from ..frames import vector_to_radec
from ._atomic import atomic_path

MAX_SIP_ORDER = 13
GRID_POINTS = 61


@dataclass(frozen=True)
class SipFit:
    """The SIP polynomials of a camera: ``{(p, q): coefficient}`` per axis, and how well they fit."""

    order: int
    a: dict[tuple[int, int], float]
    b: dict[tuple[int, int], float]
    ap: dict[tuple[int, int], float]
    bp: dict[tuple[int, int], float]
    max_residual_px: float
    """Largest error of the forward (A, B) fit over the image grid, pixels."""


def _terms(order: int) -> list[tuple[int, int]]:
    return [(p, n - p) for n in range(2, order + 1) for p in range(n, -1, -1)]


def _fit_poly(u: NDArray, v: NDArray, target: NDArray, order: int, scale: float):
    """Least-squares polynomial (terms of degree 2..order) of ``target`` (N, 2); returns the
    coefficients per axis in pixel units and the largest residual."""
    terms = _terms(order)
    design = np.stack([(u / scale) ** p * (v / scale) ** q for p, q in terms], axis=1)
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = float(np.max(np.hypot(*(design @ coef - target).T)))
    per_px = np.array([scale ** -(p + q) for p, q in terms])
    return [dict(zip(terms, (coef[:, k] * per_px).tolist(), strict=True)) for k in range(2)], residual


def _grid(camera: Camera) -> tuple[NDArray, NDArray]:
    xs = np.linspace(-0.5, camera.width - 0.5, GRID_POINTS)
    ys = np.linspace(-0.5, camera.height - 0.5, GRID_POINTS)
    gx, gy = np.meshgrid(xs, ys)
    return gx.ravel(), gy.ravel()


def fit_sip(camera: Camera, max_residual_px: float = 0.01, order: int | None = None) -> SipFit:
    """SIP polynomials of ``camera``'s distortion over its image (see the module docstring).

    Parameters
    ----------
    camera : Camera
    max_residual_px : float
        The order is the lowest from 2 to 13 whose forward fit stays within this over the image.
    order : int, optional
        Use this order instead of choosing one.
    """
    _check_camera(camera)
    if not (isinstance(max_residual_px, int | float) and math.isfinite(max_residual_px) and max_residual_px > 0):
        raise InvalidInputError(f"max_residual_px must be a positive number of pixels, got {max_residual_px!r}")
    if order is not None and not (isinstance(order, int) and not isinstance(order, bool)
                                  and 2 <= order <= MAX_SIP_ORDER):
        raise InvalidInputError(f"order must be None or a whole number from 2 to {MAX_SIP_ORDER}, got {order!r}")
    x, y = _grid(camera)
    v = camera.pixel_to_vector(x, y)
    u, w = x - camera.cx, y - camera.cy
    up, wp = camera.x_sign * camera.fx * v[:, 0] / v[:, 2], camera.fy * v[:, 1] / v[:, 2]
    scale = 0.5 * max(camera.width, camera.height)
    orders = [order] if order is not None else range(2, MAX_SIP_ORDER + 1)
    for n in orders:
        (a, b), residual = _fit_poly(u, w, np.stack([up - u, wp - w], axis=1), n, scale)
        if residual <= max_residual_px or n == orders[-1]:
            (ap, bp), _ = _fit_poly(up, wp, np.stack([u - up, w - wp], axis=1), n, scale)
            return SipFit(order=n, a=a, b=b, ap=ap, bp=bp, max_residual_px=residual)
    raise AssertionError("unreachable")  # pragma: no cover


def _check_camera(camera: Camera) -> None:
    if not isinstance(camera, Camera):
        raise InvalidInputError(f"camera must be a startrack.Camera, got {type(camera).__name__}")


def _date_obs(date_obs: str) -> Time:
    try:
        return Time(date_obs, scale="utc")
    except (ValueError, TypeError):
        raise InvalidInputError(f"date_obs must be an ISO 8601 UTC time such as 2024-08-12T03:15:00, "
                                f"got {date_obs!r}") from None


def _cd_matrix(rot_cam_from_icrs: Rotation, camera: Camera, ra: float, dec: float) -> NDArray:
    east = np.array([-np.sin(ra), np.cos(ra), 0.0])
    north = np.array([-np.sin(dec) * np.cos(ra), -np.sin(dec) * np.sin(ra), np.cos(dec)])
    e_cam, n_cam = rot_cam_from_icrs.apply(east), rot_cam_from_icrs.apply(north)
    fx = camera.x_sign * camera.fx  # a mirrored image's x runs against the camera's x axis
    return np.degrees(np.array([[e_cam[0] / fx, e_cam[1] / camera.fy],
                                [n_cam[0] / fx, n_cam[1] / camera.fy]]))


def wcs_header(rot_cam_from_icrs: Rotation, camera: Camera, *, date_obs: str | None = None,
               max_residual_px: float = 0.01) -> fits.Header:
    """A FITS header with the TAN(-SIP) WCS of an image taken by ``camera`` at this attitude.

    Parameters
    ----------
    rot_cam_from_icrs : Rotation
    camera : Camera
        With its distortion; a camera without distortion gives a plain TAN WCS.
    date_obs : str, optional
        ISO 8601 UTC time, written as DATE-OBS.
    max_residual_px : float
        Accuracy asked of the SIP fit (see :func:`fit_sip`).
    """
    if not isinstance(rot_cam_from_icrs, Rotation) or not rot_cam_from_icrs.single:
        raise InvalidInputError("rot_cam_from_icrs must be a single scipy Rotation")
    _check_camera(camera)
    time = None if date_obs is None else _date_obs(date_obs)
    axis = rot_cam_from_icrs.inv().apply([0.0, 0.0, 1.0])
    ra, dec = (float(a) for a in vector_to_radec(axis))
    cd = _cd_matrix(rot_cam_from_icrs, camera, ra, dec)
    sip = fit_sip(camera, max_residual_px) if camera.has_distortion else None
    suffix = "-SIP" if sip else ""
    hdr = fits.Header()
    cards = [("WCSAXES", 2, "two celestial axes"), ("CTYPE1", "RA---TAN" + suffix, "gnomonic projection"),
             ("CTYPE2", "DEC--TAN" + suffix, "gnomonic projection"), ("RADESYS", "ICRS", ""),
             ("CRVAL1", np.degrees(ra), "RA of the optical axis, deg"),
             ("CRVAL2", np.degrees(dec), "Dec of the optical axis, deg"),
             ("CRPIX1", camera.cx + FITS_PIXEL_OFFSET, "principal point x, FITS 1-based"),
             ("CRPIX2", camera.cy + FITS_PIXEL_OFFSET, "principal point y, FITS 1-based"),
             ("CUNIT1", "deg", ""), ("CUNIT2", "deg", ""),
             ("CD1_1", cd[0, 0], ""), ("CD1_2", cd[0, 1], ""), ("CD2_1", cd[1, 0], ""), ("CD2_2", cd[1, 1], ""),
             ("IMAGEW", camera.width, "image width, px"), ("IMAGEH", camera.height, "image height, px")]
    for key, value, comment in cards:
        hdr[key] = (value, comment)
    if time is not None:
        hdr["DATE-OBS"] = (time.isot, "UTC")
        hdr["MJD-OBS"] = (time.mjd, "UTC")
    if sip:
        _add_sip(hdr, sip)
    hdr.add_history("startrack: TAN-SIP WCS from the camera model and attitude (startrack.io._wcs)")
    return hdr


def _add_sip(hdr: fits.Header, sip: SipFit) -> None:
    for name, coeffs in (("A", sip.a), ("B", sip.b), ("AP", sip.ap), ("BP", sip.bp)):
        hdr[f"{name}_ORDER"] = sip.order
        for (p, q), value in coeffs.items():
            hdr[f"{name}_{p}_{q}"] = value
    hdr["SIPFITPX"] = (sip.max_residual_px, "largest SIP fit error over the image, px")


def solution_wcs(rot_cam_from_icrs: Rotation, camera: Camera, **kwargs) -> WCS:
    """An ``astropy.wcs.WCS`` of the image (see :func:`wcs_header`)."""
    return WCS(wcs_header(rot_cam_from_icrs, camera, **kwargs))


def write_wcs(path: str | os.PathLike, rot_cam_from_icrs: Rotation, camera: Camera, *,
              inputs: Iterable[str | os.PathLike] = (), **kwargs) -> Path:
    """Write a header-only FITS file (like astrometry.net's ``.wcs``) with the image's WCS.

    ``path`` is written by the rules of :mod:`startrack.io._atomic`: never over one of ``inputs``
    (nor, in a ``startrack`` command, over a file it read), replaced only by a complete file.
    """
    hdr = wcs_header(rot_cam_from_icrs, camera, **kwargs)
    with atomic_path(path, inputs=inputs) as tmp:
        fits.PrimaryHDU(header=hdr).writeto(tmp, overwrite=True)
    return Path(path)


def read_wcs(path: str | os.PathLike) -> WCS:
    """The WCS of a FITS file's primary header (ours or astrometry.net's ``.wcs``).

    A header-only file (NAXIS = 0) gets the image size from IMAGEW / IMAGEH instead, so astropy
    does not warn that the WCS has more axes than the (absent) image.
    """
    with fits.open(path) as hdus:
        hdr = hdus[0].header.copy()
    for key in ("NAXIS", "NAXIS1", "NAXIS2"):
        hdr.remove(key, ignore_missing=True)
    wcs = WCS(hdr)
    if "IMAGEW" in hdr and "IMAGEH" in hdr:
        wcs.pixel_shape = (int(hdr["IMAGEW"]), int(hdr["IMAGEH"]))
    return wcs
