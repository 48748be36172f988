"""Read an image file (FITS, PNG, JPEG, TIFF) or an array into a single-channel :class:`Image`.

The format is recognised by the file's first bytes, not by its extension. Pixel values keep
their native dtype and are never rescaled; colour is reduced to one channel by the rule of
:mod:`startrack.io._channels`. Pixel ``data[y, x]`` is the pixel centred at (x, y) in the
0-based convention of :mod:`startrack.conventions`.
"""

from __future__ import annotations

import gzip
import os
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ImageReadError, InvalidInputError
from ._channels import channel_index, planes_summed, to_single_channel
from ._heif import is_heif
from ._limits import check_image_size, resolve_max_pixels
from ._raster import identify_format, read_raster
from ._targets import note_input

SUPPORTED_FORMATS = ("FITS", "XISF", "PNG", "JPEG", "TIFF", "HEIF", "WEBP", "AVIF", "BMP")
GZIP_MAGIC = b"\x1f\x8b"
_SIGNATURES = {
    b"SIMPLE  =": "FITS",
    GZIP_MAGIC: "FITS",  # gzip-compressed FITS (astropy decompresses it)
    b"\x89PNG\r\n\x1a\n": "PNG",
    b"\xff\xd8\xff": "JPEG",
    b"II*\x00": "TIFF",
    b"MM\x00*": "TIFF",
    b"XISF0100": "XISF",
}


@dataclass(frozen=True)
class Image:
    """A single-channel image and what its file said about it.

    Attributes
    ----------
    data : ndarray, shape (H, W)
        Pixel values in the file's dtype (uint8, uint16, int32, float32, float64), never
        rescaled; for colour summed as R + G + B a wider type that cannot overflow (8-bit RGB
        gives uint16 0..765, 16-bit RGB gives uint32; see :mod:`startrack.io._channels`).
    path : Path or None
        The file read, None for an array.
    header : dict
        FITS header cards, or EXIF fields by their standard names (e.g. ``DateTimeOriginal``,
        ``ExposureTime``) and simple Pillow info items. Empty for an array.
    bit_depth : int or None
        Bits per sample in the source file (1, 8, 16, 32 or 64); for an array, its item size
        in bits.
    colour : bool
        True if the source had colour channels (RGB or RGBA) that were reduced to one, or was a
        colour-filter mosaic (:attr:`mosaic`).
    compression_step : float
        For a JPEG, its quantization step at the lowest spatial frequencies
        (:func:`startrack.io._raster.jpeg_step`) in the units of ``data``: three times the
        luminance's when the colour planes are summed. 0.0 for a lossless file or an array.
        Detection raises its noise floor to match (:func:`startrack.detect.compression_noise_floor`).
    mosaic : str or None
        For a FITS frame or a camera RAW file of a colour-filter mosaic, read at full resolution
        as :mod:`startrack.io._mosaic` (and :mod:`startrack.io._cfa`) says (``data`` is then
        float32): the pattern of its first cell ("RGGB", ...; the rows of a longer one joined by
        "/", e.g. an X-Trans sensor's "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"), or "unknown"
        when a FITS header names none and the pixels showed it. None for any other image.
    """

    data: NDArray
    path: Path | None = None
    header: dict[str, Any] = field(default_factory=dict)
    bit_depth: int | None = None
    colour: bool = False
    compression_step: float = 0.0
    mosaic: str | None = None

    @property
    def height(self) -> int:
        """Number of rows (pixels along y)."""
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        """Number of columns (pixels along x)."""
        return int(self.data.shape[1])


MAX_ABS_VALUE = 1e30
"""Largest magnitude of a finite pixel value: detection works in float32 (up to 3.4e38) and needs
room for sums; an image with larger values is refused rather than overflowing."""


def check_pixel_values(data: NDArray, source: object) -> None:
    """Refuse a float image with a finite value beyond +-:data:`MAX_ABS_VALUE`.

    NaN and infinite pixels are allowed (the detector ignores them as missing).

    Raises
    ------
    ImageReadError
        Naming ``source`` and the largest value found.
    """
    if data.dtype.kind != "f" or data.size == 0:
        return
    finite = np.isfinite(data)
    hi = float(np.max(data, where=finite, initial=-np.inf))
    lo = float(np.min(data, where=finite, initial=np.inf))
    worst = max(abs(hi) if np.isfinite(hi) else 0.0, abs(lo) if np.isfinite(lo) else 0.0)
    if worst > MAX_ABS_VALUE:
        raise ImageReadError(f"{source}: pixel values reach {worst:.3g}; startrack reads values up to "
                             f"+-{MAX_ABS_VALUE:g} (rescale the image, e.g. to counts)")


def _unmasked(array: np.ndarray) -> np.ndarray:
    """A masked array's data with the masked pixels as NaN (a float copy); other arrays as they are."""
    if not isinstance(array, np.ma.MaskedArray):
        return array
    mask = np.ma.getmaskarray(array)
    data = np.ma.getdata(array)
    if not mask.any():
        return data
    wide = data.dtype.kind == "f" and data.dtype.itemsize >= 8 or data.dtype.itemsize > 2
    out = data.astype(np.float64 if wide else np.float32)
    out[mask] = np.nan
    return out


def _from_array(array: np.ndarray, channel: str | int | None, max_pixels: int | None) -> Image:
    if array.dtype.kind not in "uif":
        raise InvalidInputError(f"image array must be integer or float, got dtype {array.dtype}")
    if array.size == 0:
        raise InvalidInputError(f"image array must not be empty, got shape {array.shape}")
    if array.ndim >= 2:
        check_image_size(array.shape[1], array.shape[0], max_pixels, "image array")
    bits = array.dtype.itemsize * 8
    array = _unmasked(array)
    colour = array.ndim == 3 and array.shape[-1] >= 3
    data = to_single_channel(array, channel)
    check_pixel_values(data, "image array")
    return Image(data, None, {}, bits, colour)


def _sniff(path: Path) -> str:
    """The format named by the file's first bytes; raises for missing, empty or non-image files."""
    if not path.exists():
        raise ImageReadError(f"{path}: file does not exist")
    if not path.is_file():
        raise ImageReadError(f"{path}: is not a regular file")
    try:
        with open(path, "rb") as fh:
            head = fh.read(16)
    except OSError as exc:
        raise ImageReadError(f"{path}: cannot be read ({exc.strerror})") from exc
    if not head:
        raise ImageReadError(f"{path}: file is empty (0 bytes)")
    for signature, name in _SIGNATURES.items():
        if head.startswith(signature):
            if signature == GZIP_MAGIC:
                _check_gzip_holds_fits(path)
            return name
    if is_heif(head):
        return "HEIF"
    if (container := pillow_raster_format(head)) is not None:
        return container
    other = identify_format(path)
    if other is not None:
        raise ImageReadError(
            f"{path}: unsupported image format {other}; supported: {', '.join(SUPPORTED_FORMATS)}"
        )
    raise ImageReadError(
        f"{path}: not an image file (no {', '.join(SUPPORTED_FORMATS)} signature; it starts "
        f"with {head[:12]!r})"
    )


AVIF_BRANDS = frozenset({b"avif", b"avis"})
"""``ftyp`` major brands of AVIF files (AV1-coded still images and sequences)."""


def pillow_raster_format(head: bytes) -> str | None:
    """"WEBP", "AVIF" or "BMP" when a file's first 12 bytes are that format's signature: a RIFF
    container of WebP, an ISO ``ftyp`` box of an AVIF brand, a bitmap's "BM"; else None."""
    if head[:4] == b"RIFF" and head[8:12] == b"WEBP":
        return "WEBP"
    if head[4:8] == b"ftyp" and head[8:12] in AVIF_BRANDS:
        return "AVIF"
    return "BMP" if head[:2] == b"BM" else None


def _check_gzip_holds_fits(path: Path) -> None:
    """Refuse a gzip file whose content is not FITS (a gzipped JPEG, say), naming what it holds;
    a damaged gzip stream is left for the FITS reader to report."""
    try:
        with gzip.open(path, "rb") as fh:
            inner = fh.read(16)
    except (OSError, EOFError, zlib.error):
        return
    if inner.startswith(b"SIMPLE  =") or not inner:
        return
    held = next((name for signature, name in _SIGNATURES.items() if inner.startswith(signature)), None)
    raise ImageReadError(f"{path}: a gzip file holding {held or 'something other than FITS'}; only gzip-compressed "
                         "FITS is read: decompress it first (gunzip)")


RAW_SUFFIXES = frozenset({".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw"})
"""Camera RAW file names, decoded through rawpy by :func:`startrack.io._raw.read_raw_plane` (the
mosaic at full resolution, as :mod:`startrack.io._mosaic` reads a FITS one)."""
IMAGE_SUFFIXES = frozenset({".fits", ".fit", ".fts", ".xisf", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".heic",
                            ".heif", ".webp", ".avif", ".bmp", *RAW_SUFFIXES})
"""File names that folders of images are searched for (the reader then checks the content)."""


def _raw_channel(channel: str | int | None) -> str | None:
    index = channel_index(channel)
    return None if index is None else "rgb"[index]


def read_image(
    source: str | os.PathLike | np.ndarray, *, channel: str | int | None = None,
    max_pixels: int | None = None,
) -> Image:
    """Read an image file or wrap an array, reduced to a single channel.

    Parameters
    ----------
    source : str, Path or ndarray
        A FITS, XISF (:mod:`startrack.io._xisf`), PNG, JPEG or TIFF file (8 or 16 bit, grey or
        colour; float FITS / XISF / TIFF), a HEIC / HEIF photo (through pillow-heif,
        :mod:`startrack.io._heif`), a camera RAW file (:data:`RAW_SUFFIXES`, through rawpy, at
        full resolution), or an array of shape (H, W) or (H, W, C) with C = 1 (grey), 2 (grey +
        alpha), 3 (RGB) or 4 (RGBA).
    channel : {None, "r", "g", "b", 0, 1, 2}
        Colour rule: None sums R + G + B in a wider type (uint8 -> uint16, uint16 -> uint32,
        floats in their own precision); otherwise that plane is kept in its native dtype.
        Alpha is always ignored; grey images check ``channel`` and then ignore it.
    max_pixels : int, optional
        Largest width x height accepted, checked from the file's header before any pixel is
        decoded (:mod:`startrack.io._limits`); None uses the limit in force (100 million pixels
        unless ``--max-pixels`` or ``STARTRACK_MAX_PIXELS`` raised it).

    Returns
    -------
    Image
        ``data`` of shape (H, W); the first 2-D image HDU for FITS. The masked pixels of a
        ``numpy.ma.MaskedArray`` become NaN (in a float copy), which detection leaves out.

    Raises
    ------
    ImageReadError
        If the file is missing, empty, truncated, corrupt, not an image, of an unsupported
        format, larger than ``max_pixels``, or has values beyond +-1e30; the message names the
        file and the problem.
    InvalidInputError
        If ``channel`` or ``max_pixels`` is not valid, or an array is empty, not integer /
        float, or not 2-D or 3-D with 1 to 4 channels.
    """
    channel_index(channel)  # checked before any file is read
    resolve_max_pixels(max_pixels)
    if isinstance(source, np.ndarray):
        return _from_array(source, channel, max_pixels)
    if not isinstance(source, str | os.PathLike):
        raise InvalidInputError(
            f"source must be a file path or a numpy array, got {type(source).__name__}"
        )
    path = Path(source)
    if path.suffix.lower() in RAW_SUFFIXES:
        from ._raw import read_raw_plane  # needs rawpy (the "raw" extra); says so if it is missing

        note_input(path)
        return read_raw_plane(path, channel=_raw_channel(channel), max_pixels=max_pixels)
    kind = _sniff(path)
    note_input(path)
    step, mosaic = 0.0, None  # a JPEG's quantization step (lossless formats have none); a Bayer mosaic's pattern
    if kind == "FITS":
        from ._fitsfile import read_fits  # astropy.io.fits: loaded only for FITS files
        from ._mosaic import from_mosaic

        data, header, bit_depth = read_fits(path, max_pixels)
        data, mosaic = from_mosaic(data, header, channel_index(channel))
    elif kind == "XISF":
        from ._mosaic import from_mosaic
        from ._xisf import read_xisf  # PixInsight's format, read from its specification

        data, header, bit_depth = read_xisf(path, max_pixels)
        data, mosaic = from_mosaic(data, header, channel_index(channel))
    elif kind == "HEIF":
        from ._heif import read_heif  # pillow-heif (the "heif" extra): loaded only for HEIF files

        data, header, bit_depth = read_heif(path, max_pixels)
    else:
        data, header, bit_depth, step = read_raster(path, max_pixels, kind=kind)
    colour = data.ndim == 3
    single = to_single_channel(data, channel)
    check_pixel_values(single, path)
    # each colour plane of a JPEG carries its luminance's steps (its chroma planes' own are not counted)
    return Image(single, path, header, bit_depth, colour or mosaic is not None, step * planes_summed(data, channel),
                 mosaic)
