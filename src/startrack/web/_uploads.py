"""Uploads: the body read while it streams with a size limit, the type sniffed from the content,
and the image's dimensions read from its header before anything is decoded.

1. **Size** (413): a ``Content-Length`` above the limit is refused before one byte is read; a
   body without one (chunked) is counted chunk by chunk and refused as soon as it passes it.
2. **Type** (415): the first bytes must carry a FITS, PNG, JPEG or TIFF signature or a camera
   RAW one; the client's file name is never trusted for the type (it only chooses between TIFF
   and a TIFF-based RAW with the same signature, and names the RAW decoder).
3. **Dimensions** (422, field ``file``): from the header alone (Pillow's lazy ``Image.open``,
   the FITS ``NAXISn`` / ``ZNAXISn`` cards read here, block by block, without astropy, which
   would look at the data's size; LibRaw's ``sizes`` without unpacking), each side within
   :data:`~.config.MIN_SIDE_PX`..:data:`~.config.MAX_SIDE_PX` and at most ``max_pixels`` in all.

The stored file is named by the server (``input.<ext>``, the extension from the sniffed type);
the client's file name is kept only as a display label, stripped of any folder part and control
characters.
"""

from __future__ import annotations

import gzip
import hashlib
import math
import re
import warnings
from collections.abc import AsyncGenerator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from PIL import Image as PILImage
from starlette.datastructures import UploadFile
from starlette.formparsers import MultiPartException, MultiPartParser
from starlette.requests import Request

from ..io import BITPIX_VALUES, RAW_SUFFIXES, is_heif, pillow_raster_format, xisf_size
from ._config import MAX_SIDE_PX, MIN_SIDE_PX
from ._refusals import Refusal, bad_request

SIGNATURES: tuple[tuple[bytes, str], ...] = (
    (b"SIMPLE  =", "fits"), (b"\x1f\x8b", "fits"), (b"\x89PNG\r\n\x1a\n", "png"), (b"\xff\xd8\xff", "jpeg"),
    (b"II*\x00", "tiff"), (b"MM\x00*", "tiff"), (b"XISF0100", "xisf"), (b"IIRO", "raw"), (b"IIRS", "raw"),
    (b"MMOR", "raw"), (b"IIU\x00", "raw"), (b"FUJIFILMCCD-RAW", "raw"),
)
"""Leading bytes of each accepted format (RAW: Olympus ORF, Panasonic RW2, Fuji RAF; CR3 is an
ISO media file, ``ftypcrx`` at offset 4; DNG, NEF, CR2, ARW, PEF and SRW are TIFF containers)."""
EXTENSIONS = {"fits": ".fits", "png": ".png", "jpeg": ".jpg", "tiff": ".tif", "heif": ".heic", "webp": ".webp",
              "avif": ".avif", "bmp": ".bmp", "xisf": ".xisf"}
RAW_SIGNATURE_SUFFIXES = ((b"IIRO", ".orf"), (b"IIRS", ".orf"), (b"MMOR", ".orf"), (b"IIU\x00", ".rw2"),
                          (b"FUJIFILMCCD-RAW", ".raf"))
FITS_BLOCK = 2880
FITS_MAX_BLOCKS = 200
FITS_MAX_HDUS = 8
MAX_FILES = 200
MAX_FIELDS = 200
MAX_FIELD_BYTES = 65_536
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


@dataclass(frozen=True)
class StoredImage:
    """An accepted upload: where the server put it and what it is."""

    path: Path
    label: str
    format: str
    sha256: str
    n_bytes: int
    width: int
    height: int


async def _limited(request: Request, limit: int) -> AsyncGenerator[bytes, None]:
    seen = 0
    async for chunk in request.stream():
        seen += len(chunk)
        if seen > limit:
            raise too_large(limit, f"more than {limit} bytes arrived")
        yield chunk


def too_large(limit: int, what: str) -> Refusal:
    return Refusal(413, f"the upload is too large: {what}; the limit is {limit / 1e6:g} MB (--max-upload-mb)")


async def read_form(request: Request, limit: int) -> tuple[dict[str, list[str]], list[UploadFile]]:
    """The fields and files of a ``multipart/form-data`` body, read with the size limit.

    Returns the text fields (name -> values) and the file parts (spooled to temporary files)."""
    if not request.headers.get("content-type", "").lower().startswith("multipart/form-data"):  # any case
        raise Refusal(415, "send the image as multipart/form-data with a 'file' part")
    length = request.headers.get("content-length")
    if length is not None and length.isdigit() and int(length) > limit:
        raise too_large(limit, f"Content-Length is {int(length)} bytes")
    parser = MultiPartParser(request.headers, _limited(request, limit), max_files=MAX_FILES,
                             max_fields=MAX_FIELDS, max_part_size=MAX_FIELD_BYTES)
    try:
        form = await parser.parse()
    except MultiPartException as exc:
        raise bad_request(f"malformed multipart body: {exc}") from None
    fields: dict[str, list[str]] = {}
    files: list[UploadFile] = []
    for key, value in form.multi_items():
        if isinstance(value, str):
            fields.setdefault(key, []).append(value)
        else:
            if key == "file":
                files.append(value)
            else:
                value.file.close()
    return fields, files


def display_label(filename: str | None) -> str:
    """The client's file name for display only: no folder part, no control characters, 100 chars."""
    name = (filename or "upload").replace("\\", "/").rsplit("/", 1)[-1]
    return _CONTROL.sub("", name)[:100] or "upload"


def sniff(head: bytes, label: str) -> str:
    """"fits", "xisf", "png", "jpeg", "tiff", "heif", "webp", "avif", "bmp" or "raw" from the first
    bytes; 415 otherwise."""
    if head[4:12] == b"ftypcrx ":
        return "raw"
    if is_heif(head):
        return "heif"
    if (other := pillow_raster_format(head)) is not None:
        return other.lower()
    for signature, kind in SIGNATURES:
        if head.startswith(signature):
            if kind == "tiff" and Path(label).suffix.lower() in RAW_SUFFIXES:
                return "raw"
            return kind
    shown = head[:12]
    raise Refusal(415, f"unsupported file type: {label!r} is not FITS, XISF, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP "
                       f"or camera RAW (it starts with {shown!r})", "file")


def raw_suffix(head: bytes, label: str) -> str:
    """The RAW file name suffix the decoder needs: from the signature when it names the maker's
    format, else the client's (a TIFF-based RAW, whose suffix :func:`sniff` has checked)."""
    for signature, suffix in RAW_SIGNATURE_SUFFIXES:
        if head.startswith(signature):
            return suffix
    return ".cr3" if head[4:12] == b"ftypcrx " else Path(label).suffix.lower()


def store_upload(upload: UploadFile, folder: Path, stem: str, max_pixels: int) -> StoredImage:
    """Copy a file part into ``folder`` as ``<stem><ext>``, checked (module docstring)."""
    label = display_label(upload.filename)
    upload.file.seek(0)
    head = upload.file.read(32)
    kind = sniff(head, label)
    suffix = raw_suffix(head, label) if kind == "raw" else EXTENSIONS[kind]
    path = folder / f"{stem}{suffix}"
    digest, n_bytes = hashlib.sha256(), 0
    upload.file.seek(0)
    with open(path, "wb") as out:
        while chunk := upload.file.read(1 << 20):
            digest.update(chunk)
            n_bytes += len(chunk)
            out.write(chunk)
    upload.file.close()
    width, height = image_size(path, kind, label)
    check_size(width, height, max_pixels, label)
    return StoredImage(path, label, kind, digest.hexdigest(), n_bytes, width, height)


def copy_local(source: Path, folder: Path, stem: str, max_pixels: int) -> StoredImage:
    """As :func:`store_upload` for a file of the ``--root`` folder."""
    with open(source, "rb") as fh:
        upload = UploadFile(file=fh, filename=source.name)  # closed by store_upload
        return store_upload(upload, folder, stem, max_pixels)


def check_size(width: int, height: int, max_pixels: int, label: str) -> None:
    """422 (field ``file``) for a side outside the limits or too many pixels."""
    if not (MIN_SIDE_PX <= width <= MAX_SIDE_PX and MIN_SIDE_PX <= height <= MAX_SIDE_PX) \
            or width * height > max_pixels:
        raise Refusal(422, f"{label!r} is {width} x {height} px; images must be {MIN_SIDE_PX} to {MAX_SIDE_PX} px "
                           f"a side and at most {max_pixels / 1e6:g} Mpx", "file")


def image_size(path: Path, kind: str, label: str) -> tuple[int, int]:
    """Width and height from the header only; 415 when the header cannot be read."""
    try:
        if kind == "fits":
            return _fits_size(path)
        if kind == "raw":
            return _raw_size(path)
        if kind == "heif":
            return _heif_size(path)
        if kind == "xisf":
            return xisf_size(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PILImage.DecompressionBombWarning)
            with PILImage.open(path) as image:  # lazy: reads the header, decodes nothing
                return image.size
    except PILImage.DecompressionBombError as exc:
        found = re.search(r"\((\d+) pixels\)", str(exc))
        pixels = found.group(1) if found else "too many"
        raise Refusal(422, f"{label!r} has {pixels} pixels; images must be at most {MAX_SIDE_PX} px a side",
                      "file") from None
    except Refusal:
        raise
    except Exception as exc:  # any reader's complaint about a header means "not an image we read"
        said = " ".join(str(exc).split()).replace(str(path), label)  # not the server's own folder
        raise Refusal(415, f"{label!r} has the signature of {kind.upper()} but its header cannot be read: "
                           f"{said[:200]}", "file") from None


def _heif_size(path: Path) -> tuple[int, int]:
    """Width and height of a HEIF file's primary image from its boxes (pillow-heif decodes nothing
    until the pixels are asked for)."""
    import pillow_heif  # the "heif" extra; its absence is a header that cannot be read (415)

    width, height = pillow_heif.open_heif(path).size
    return int(width), int(height)


def _fits_size(path: Path) -> tuple[int, int]:
    """Width and height of the first image HDU (or tile-compressed image) from the header cards,
    reading at most :data:`FITS_MAX_BLOCKS` blocks per header and nothing of the data."""
    with open(path, "rb") as probe:
        compressed = probe.read(2) == b"\x1f\x8b"
    with (gzip.open if compressed else open)(path, "rb") as fh:
        for _ in range(FITS_MAX_HDUS):
            cards = _fits_cards(fh)
            if cards is None:
                break
            if cards.get("ZIMAGE") is True and int(cards.get("ZNAXIS", 0)) >= 2:
                return int(cards["ZNAXIS1"]), int(cards["ZNAXIS2"])
            naxis = int(cards.get("NAXIS", 0))
            if naxis >= 2 and cards.get("XTENSION", "IMAGE") == "IMAGE":
                if cards.get("BITPIX") not in BITPIX_VALUES:  # the reader refuses it: refuse it now, not in the worker
                    raise ValueError(f"BITPIX = {cards.get('BITPIX')!r}; FITS allows 8, 16, 32, 64, -32, -64")
                return int(cards["NAXIS1"]), int(cards["NAXIS2"])
            size = abs(int(cards.get("BITPIX", 8))) // 8 * int(cards.get("GCOUNT", 1)) * (
                int(cards.get("PCOUNT", 0)) + (math.prod(int(cards[f"NAXIS{i}"]) for i in range(1, naxis + 1))
                                               if naxis else 0))
            fh.seek(-(-size // FITS_BLOCK) * FITS_BLOCK, 1)
    raise ValueError("no image HDU with NAXIS >= 2")


def _fits_cards(fh) -> dict[str, Any] | None:
    """The keyword values of one FITS header (integers, logicals and strings), up to END; None at
    the end of the file."""
    cards: dict[str, Any] = {}
    for n in range(FITS_MAX_BLOCKS):
        block = fh.read(FITS_BLOCK)
        if n == 0 and not block:
            return None
        if len(block) < FITS_BLOCK:
            raise ValueError("the FITS header ends before its END card")
        for i in range(0, FITS_BLOCK, 80):
            card = block[i:i + 80].decode("ascii", errors="replace")
            key = card[:8].strip()
            if key == "END":
                return cards
            if card[8:10] == "= ":
                cards[key] = _fits_value(card[10:])
    raise ValueError(f"the FITS header is longer than {FITS_MAX_BLOCKS} blocks")


def _fits_value(text: str) -> Any:
    text = text.split("/", 1)[0].strip() if not text.lstrip().startswith("'") else text.strip()
    if text in ("T", "F"):
        return text == "T"
    if text.startswith("'"):
        return text[1:].split("'", 1)[0].strip()
    try:
        return int(text)
    except ValueError:
        return text


def _raw_size(path: Path) -> tuple[int, int]:
    import rawpy

    raw = rawpy.RawPy()
    try:
        raw.open_file(str(path))
        sizes = raw.sizes
        return int(sizes.width), int(sizes.height)  # the visible area, as the reader checks and reads it
    finally:
        raw.close()
