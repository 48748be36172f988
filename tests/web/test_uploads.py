"""Content sniffing and header-only dimensions (no server): every accepted signature, RAW suffixes
from the content, FITS sizes from plain, gzipped, tile-compressed and simulated files."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
from astropy.io import fits

from startrack.web._refusals import Refusal
from startrack.web._uploads import check_size, display_label, image_size, raw_suffix, sniff


@pytest.mark.parametrize(("head", "label", "kind"), [
    (b"SIMPLE  =                    T", "x.dat", "fits"), (b"\x1f\x8b\x08\x00", "x.fits.gz", "fits"),
    (b"\x89PNG\r\n\x1a\n\x00", "x.jpg", "png"), (b"\xff\xd8\xff\xe0", "x.png", "jpeg"),
    (b"II*\x00\x08\x00", "x.tif", "tiff"), (b"MM\x00*\x00", "x", "tiff"), (b"II*\x00\x08\x00", "x.NEF", "raw"),
    (b"IIRO\x08\x00", "x.jpg", "raw"), (b"\x00\x00\x00\x18ftypcrx \x00", "x", "raw"),
    (b"\x00\x00\x00\x1cftypheic\x00\x00\x00\x00", "x.jpg", "heif"), (b"\x00\x00\x00\x18ftypmif1\x00", "x", "heif"),
    (b"XISF0100\x10\x00\x00\x00", "x.fits", "xisf"),
])
def test_the_type_comes_from_the_bytes(head, label, kind):
    assert sniff(head, label) == kind


def test_unknown_bytes_are_415_whatever_the_name():
    with pytest.raises(Refusal) as refused:
        sniff(b"GIF89a\x00\x00", "photo.png")
    assert refused.value.status == 415 and refused.value.field == "file"


def test_raw_suffix_names_the_decoder_from_the_content():
    assert raw_suffix(b"IIRO\x08\x00", "x.jpg") == ".orf"
    assert raw_suffix(b"FUJIFILMCCD-RAW 0201", "x") == ".raf"
    assert raw_suffix(b"\x00\x00\x00\x18ftypcrx ", "x.bin") == ".cr3"
    assert raw_suffix(b"II*\x00", "IMG_1.DNG") == ".dng"


def test_display_label_drops_folders_and_control_characters():
    assert display_label("../../etc/passwd") == "passwd"
    assert display_label("C:\\Users\\me\\night\x07.jpg") == "night.jpg"
    assert display_label("") == "upload" and len(display_label("a" * 500)) == 100


def test_check_size_limits():
    check_size(507, 507, 100_000_000, "ok.jpg")
    for width, height in ((15, 100), (100, 40_001), (12_000, 9_000)):
        with pytest.raises(Refusal) as refused:
            check_size(width, height, 100_000_000, "x.png")
        assert refused.value.status == 422 and f"is {width} x {height} px" in refused.value.message


def test_fits_sizes_from_the_header_only(tmp_path):
    data = np.zeros((30, 40), dtype=np.uint16)
    plain = tmp_path / "plain.fits"
    fits.PrimaryHDU(data).writeto(plain)
    assert image_size(plain, "fits", "plain.fits") == (40, 30)
    zipped = tmp_path / "zipped.fits.gz"
    zipped.write_bytes(gzip.compress(plain.read_bytes()))
    assert image_size(zipped, "fits", "zipped.fits.gz") == (40, 30)
    tiled = tmp_path / "tiled.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.CompImageHDU(data)]).writeto(tiled)
    assert image_size(tiled, "fits", "tiled.fits") == (40, 30)
    extension = tmp_path / "extension.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.ImageHDU(data.T)]).writeto(extension)
    assert image_size(extension, "fits", "extension.fits") == (30, 40)
    table_only = tmp_path / "table.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.BinTableHDU.from_columns([fits.Column("a", "J", array=[1])])]
                 ).writeto(table_only)
    with pytest.raises(Refusal) as refused:
        image_size(table_only, "fits", "table.fits")
    assert refused.value.status == 415 and "no image HDU" in refused.value.message


def test_a_simulated_frame_reads_its_size(tmp_path):
    from startrack.web._simulation import render, validate_simulation

    path = tmp_path / "sim.fits"
    render(validate_simulation({"width": 160, "height": 120, "fov_deg": 8.0, "seed": 3}), path)
    assert image_size(path, "fits", "sim.fits") == (160, 120)


def test_heif_size_comes_from_its_boxes(tmp_path):
    pillow_heif = pytest.importorskip("pillow_heif")
    path = tmp_path / "phone.heic"
    rgb = np.zeros((48, 72, 3), np.uint8)
    pillow_heif.from_bytes(mode="RGB", size=(72, 48), data=rgb.tobytes()).save(path, quality=50)
    assert image_size(path, sniff(path.read_bytes()[:32], "phone.heic"), "phone.heic") == (72, 48)


def test_xisf_size_comes_from_its_header(tmp_path):
    path = tmp_path / "stack.xisf"
    path.write_bytes(b"XISF0100" + (56).to_bytes(4, "little") + bytes(4)
                     + b'<xisf version="1.0"><Image geometry="72:48:1"/></xisf>'.ljust(56))
    assert image_size(path, sniff(path.read_bytes()[:32], "stack.xisf"), "stack.xisf") == (72, 48)
    path.write_bytes(path.read_bytes().replace(b"72:48:1", b"72:48:0"))
    with pytest.raises(Refusal, match="has the signature of XISF but its header cannot be read") as refused:
        image_size(path, "xisf", "stack.xisf")
    assert refused.value.status == 415
