"""PNG, JPEG, TIFF, WebP, AVIF and BMP images through Pillow, keeping native bit depths.

What each Pillow mode becomes (before the colour rule of :mod:`startrack.io._channels`):

=====================  ======================  =========
Pillow mode            array                   bit depth
=====================  ======================  =========
``1``                  uint8 0 / 1             1
``L``                  uint8                   8
``I;16`` (and B / L)   uint16                  16
``I``                  uint16 if the file      16 or 32
                       declares 16-bit
                       samples, else int32
``F``                  float32                 32
``LA``                 uint8 (alpha dropped)   8
``RGB`` / ``RGBA``     uint8 (H, W, 3 or 4)    8
``P``, ``CMYK``, ...   converted to RGB(A)     8
=====================  ======================  =========

Pillow silently keeps only the high byte of 16-bit colour samples, so 16-bit colour TIFFs are
decoded by :mod:`startrack.io._tiff` and 16-bit colour PNGs by :mod:`startrack.io._png16`. A truncated file raises
:class:`~startrack.errors.ImageReadError` even if ``PIL.ImageFile.LOAD_TRUNCATED_IMAGES`` was
set elsewhere, and so does a PNG or JPEG whose structure is whole but whose pixel data stop early
(:mod:`startrack.io._pixel_data`). EXIF orientation is recorded in the header but never applied: the array keeps
the sensor's own row and column order. Pillow decodes WebP and AVIF (lossy or lossless) to 8-bit
RGB(A), an AVIF of 10 or 12 bits too; lossy ones have no JPEG quantization step to give detection
(``compression_step`` 0).
"""

from __future__ import annotations

import struct
import threading
import warnings
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray
from PIL import ExifTags, ImageFile, TiffImagePlugin, UnidentifiedImageError
from PIL import Image as PILImage

from ..errors import ImageReadError
from ._limits import check_image_size
from ._pixel_data import JpegLayout, jpeg_layout, png_missing_data, probe_stream
from ._png16 import is_png16_colour, read_png16_colour
from ._tiff import is_tiff16_colour, read_tiff16_colour

SUPPORTED_PILLOW_FORMATS = ("PNG", "JPEG", "MPO", "TIFF", "WEBP", "AVIF", "BMP")
"""Pillow format names read here (MPO is the multi-picture JPEG some cameras write)."""

LENIENT_METADATA_FORMATS = ("JPEG", "PNG", "WEBP", "AVIF", "BMP")
"""Formats whose broken metadata (EXIF, ICC) is ignored: their pixels do not depend on it (a
TIFF's directory is its structure: there a metadata warning is an error)."""

_JPEG_FORMATS = ("JPEG", "MPO")
JPEG_LOWEST_FREQUENCIES = (1, 8)
"""Indices of the (0, 1) and (1, 0) entries of a JPEG quantization table of 64 in natural (row
by row) order, the order in which Pillow gives them."""
_UINT16_MODES = ("I;16", "I;16L", "I;16B", "I;16N")
_TO_RGB_MODES = ("P", "PA", "CMYK", "YCbCr", "LAB", "HSV", "RGBX", "RGBa")
_EXIF_IFD = 0x8769
_truncation_lock = threading.Lock()


_DECODE_ERRORS = (UnidentifiedImageError, OSError, SyntaxError, ValueError, EOFError, zlib.error,
                  UserWarning)


@contextmanager
def _strict_pillow(metadata_warnings: bool = True) -> Iterator[None]:
    """Make Pillow raise on truncated data and turn its corruption warnings into exceptions.

    ``PIL.ImageFile.LOAD_TRUNCATED_IMAGES`` is forced off (and restored) whatever it was set to
    elsewhere; Pillow's UserWarnings ("Truncated File Read", ...) become exceptions. With
    ``metadata_warnings=False`` (opening a JPEG or PNG, when Pillow parses EXIF for the resolution)
    they are ignored instead: unparsable EXIF is left out, not an error. Pillow's own pixel limit
    (``MAX_IMAGE_PIXELS``) is switched off: :mod:`startrack.io._limits` applies one limit to every
    format, from the header.
    """
    with _truncation_lock, warnings.catch_warnings():
        warnings.simplefilter("error" if metadata_warnings else "ignore", UserWarning)
        previous = ImageFile.LOAD_TRUNCATED_IMAGES, PILImage.MAX_IMAGE_PIXELS
        ImageFile.LOAD_TRUNCATED_IMAGES, PILImage.MAX_IMAGE_PIXELS = False, None
        try:
            yield
        finally:
            ImageFile.LOAD_TRUNCATED_IMAGES, PILImage.MAX_IMAGE_PIXELS = previous


def _plain(value: Any) -> Any:
    """An EXIF / info value as a plain Python value, or None if it is binary or structured."""
    if isinstance(value, bytes):  # e.g. ExifVersion b"0232"; binary blobs are dropped
        text = value.rstrip(b"\x00").decode("ascii", errors="replace")
        return text if len(text) <= 64 and text.isprintable() and "\ufffd" not in text else None
    if isinstance(value, str):
        return value.strip("\x00 ")
    if isinstance(value, bool | int | float):
        return value
    if isinstance(value, tuple) and value and all(isinstance(v, int | float) for v in value):
        return tuple(float(v) for v in value)
    try:  # PIL.TiffImagePlugin.IFDRational and other numbers
        return float(value)
    except (TypeError, ValueError, ZeroDivisionError):
        return None


def _header(image: PILImage.Image) -> dict[str, Any]:
    """EXIF fields (base and Exif IFDs, named as in the EXIF standard) and simple info items.

    The pixels are already decoded: EXIF that Pillow cannot parse is left out, not an error.
    """
    header: dict[str, Any] = {}
    for key, value in image.info.items():
        if isinstance(key, str) and key not in ("exif", "icc_profile", "xmp"):
            plain = _plain(value)
            if plain is not None:
                header[key] = plain
    return {**header, **_exif_fields(image.getexif)}


def exif_header(raw: bytes | None) -> dict[str, Any]:
    """The EXIF fields of a raw EXIF block (``Exif\\0\\0`` and a TIFF structure, as HEIF files
    carry it), named as :func:`_header` names them; empty when there is none or it cannot be
    parsed."""
    if not raw:
        return {}

    def load() -> PILImage.Exif:
        exif = PILImage.Exif()
        exif.load(raw)
        return exif

    return _exif_fields(load)


def _exif_fields(get_exif) -> dict[str, Any]:
    """The base and Exif IFD fields of the ``PIL.Image.Exif`` that ``get_exif()`` returns, as
    plain values by their EXIF names; EXIF that Pillow cannot parse is left out, not an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            exif = get_exif()
            ifds = (exif, exif.get_ifd(_EXIF_IFD))
        except (OSError, SyntaxError, ValueError, KeyError, TypeError, struct.error):
            return {}
    header: dict[str, Any] = {}
    for tags in ifds:
        for tag, value in tags.items():
            plain = _plain(value)
            if plain is not None:
                header[ExifTags.TAGS.get(tag, f"Tag{tag}")] = plain
    return header


def _declared_bits(image: PILImage.Image, head: bytes) -> int | None:
    """Bits per sample the file declares (PNG IHDR or TIFF BitsPerSample), if known."""
    if image.format == "PNG" and len(head) > 25:
        return head[24]
    if isinstance(image, TiffImagePlugin.TiffImageFile):
        bits = image.tag_v2.get(258)
        return int(max(bits) if isinstance(bits, tuple) else bits) if bits else None
    return None


def _to_array(image: PILImage.Image, declared_bits: int | None) -> tuple[NDArray, int]:
    """The decoded pixels (see the table in the module docstring) and their bit depth.

    ``declared_bits`` is what the file says (:func:`_declared_bits`); it tells a 16-bit file
    that Pillow decoded as 32-bit mode "I" from a genuine 32-bit one.
    """
    mode = image.mode
    if mode in _TO_RGB_MODES:
        has_alpha = mode == "PA" or "transparency" in image.info
        image, mode = image.convert("RGBA" if has_alpha else "RGB"), "RGB"
    if mode == "1":
        return np.asarray(image, dtype=np.uint8), 1
    if mode == "LA":
        return np.asarray(image.getchannel("L")), 8
    if mode in _UINT16_MODES:
        return np.asarray(image).astype(np.uint16), 16
    if mode == "I":
        data = np.asarray(image)
        if declared_bits == 16 and data.min() >= 0 and data.max() <= 65535:
            return data.astype(np.uint16), 16
        return data.astype(np.int32), 32
    if mode == "F":
        return np.asarray(image, dtype=np.float32), 32
    if mode in ("L", "RGB", "RGBA"):
        return np.asarray(image), 8
    raise ImageReadError(f"Pillow image mode {mode!r} is not supported")


def _load(image: PILImage.Image, path: Path, name: str) -> None:
    """Decode ``image``'s pixels (of a ``name`` file) strictly (:func:`_strict_pillow`)."""
    try:
        with _strict_pillow():
            image.load()
    except _DECODE_ERRORS as exc:
        raise ImageReadError(f"{path}: {name} file is truncated or corrupt ({exc})") from exc


@contextmanager
def _pixel_source(image: PILImage.Image, fh: BinaryIO, layout: JpegLayout | None, path: Path
                  ) -> Iterator[PILImage.Image]:
    """The image to decode: ``image``, or for a one-scan JPEG the file opened again from its
    :func:`._pixel_data.probe_stream`, which fails as truncated when the scan ends early."""
    if layout is None or not layout.single_scan:
        yield image
        return
    with _open(probe_stream(fh, layout), path, strict_metadata=False) as probe:
        yield probe


def _missing_data(image: PILImage.Image, fh: BinaryIO, layout: JpegLayout | None) -> str | None:
    """What a decoded PNG or JPEG lacks although its structure is whole (:mod:`._pixel_data`)."""
    if image.format == "PNG":
        return png_missing_data(fh)
    return None if layout is None else layout.missing_scans()


def _decode(image: PILImage.Image, head: bytes, fh: BinaryIO, path: Path) -> tuple[NDArray, int]:
    if isinstance(image, TiffImagePlugin.TiffImageFile) and is_tiff16_colour(image.tag_v2):
        return read_tiff16_colour(path, fh, image.tag_v2), 16
    if image.format == "PNG" and is_png16_colour(head):
        return read_png16_colour(path, fh), 16
    layout = jpeg_layout(fh) if image.format in _JPEG_FORMATS else None
    with _pixel_source(image, fh, layout, path) as source:
        _load(source, path, str(image.format))
        missing = _missing_data(image, fh, layout)
        if missing is not None:
            raise ImageReadError(f"{path}: {image.format} file is truncated or corrupt ({missing})")
        try:
            return _to_array(source, _declared_bits(image, head))
        except ImageReadError as exc:
            raise ImageReadError(f"{path}: {exc}") from exc


def identify_format(path: Path) -> str | None:
    """Pillow's name for the format of a file (read from its first bytes), or None if unknown."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with PILImage.open(path) as image:
                return image.format
    except (*_DECODE_ERRORS, PILImage.DecompressionBombError):
        return None


def _open(fh: BinaryIO, path: Path, strict_metadata: bool) -> PILImage.Image:
    try:
        with _strict_pillow(strict_metadata):
            return PILImage.open(fh)
    except _DECODE_ERRORS as exc:
        raise ImageReadError(f"{path}: image header is truncated or corrupt ({exc})") from exc


def read_raster(path: Path, max_pixels: int | None = None, *, kind: str | None = None
                ) -> tuple[NDArray, dict[str, Any], int, float]:
    """Decode a PNG, JPEG, TIFF, WebP, AVIF or BMP file, refusing one over the size limit from its header.

    Parameters
    ----------
    path : Path
        The file; it is read as Pillow needs it, never whole up front.
    max_pixels : int, optional
        Largest width x height (:mod:`startrack.io._limits`; None: the limit in force).
    kind : {"PNG", "JPEG", "TIFF", "WEBP", "AVIF", "BMP"}, optional
        The format its signature named; metadata warnings (broken EXIF) are ignored but for a TIFF
        (whose directory is the image's structure: :data:`LENIENT_METADATA_FORMATS`).

    Returns
    -------
    data : ndarray, shape (H, W) or (H, W, C) with C in {3, 4}
        Native dtype, never rescaled (see the module table).
    header : dict
        EXIF fields by their standard names (``DateTimeOriginal``, ``ExposureTime``, ``Model``,
        ...) and simple Pillow info items (``dpi``, PNG text chunks).
    bit_depth : int
        Bits per sample in the file.
    step : float
        A JPEG's quantization step (:func:`jpeg_step`), 0.0 for PNG and TIFF.

    Raises
    ------
    ImageReadError
        If the file is truncated or corrupt, too large, or its layout would lose bits.
    """
    with open(path, "rb") as fh:
        head = fh.read(32)
        fh.seek(0)
        with _open(fh, path, strict_metadata=kind not in LENIENT_METADATA_FORMATS) as image:
            if image.format not in SUPPORTED_PILLOW_FORMATS:
                raise ImageReadError(f"{path}: unsupported image format {image.format}")
            check_image_size(image.width, image.height, max_pixels, path)
            data, bit_depth = _decode(image, head, fh, path)
            return data, _header(image), bit_depth, jpeg_step(image)


def jpeg_step(image: PILImage.Image) -> float:
    """A JPEG's quantization step at its lowest spatial frequencies: the mean of the (0, 1) and
    (1, 0) entries of its luminance table (:data:`JPEG_LOWEST_FREQUENCIES`), in grey levels of
    its 8-bit samples; 0.0 for a lossless format.

    One step of those two coefficients is the smallest pattern the compression can add or take
    away over an 8 x 8 block: on a dark, noisy sky, noise that rounds up to a step becomes a
    smooth blob the size of a star (:func:`startrack.detect.compression_noise_floor`).
    """
    tables = getattr(image, "quantization", None) if image.format in _JPEG_FORMATS else None
    table = None if not tables else tables.get(0, next(iter(tables.values())))
    if table is None or len(table) != 64:
        return 0.0
    return float(np.mean([table[i] for i in JPEG_LOWEST_FREQUENCIES]))
