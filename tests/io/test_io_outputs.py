"""Outputs that never destroy (docs/io.md, "Outputs"): a full disk, a device, a FIFO, a link, an
input given as the output, a pair of files, a dead writer's temporary file.

A full disk is a real kernel failure: the soft ``RLIMIT_FSIZE`` of this process is lowered for
one write (Python ignores SIGXFSZ, so the write fails with EFBIG, as with ENOSPC) and restored.
"""

from __future__ import annotations

import json
import os
import resource
import stat
import subprocess
import sys
import threading
from contextlib import contextmanager

import numpy as np
import pytest

from startrack.errors import InvalidInputError, OutputError
from startrack.io import read_image, write_fits, write_png, write_tiff
from startrack.io._atomic import atomic_group, open_output, remove_stale_temps, write_output
from startrack.io._targets import note_input, output_target, protect_inputs
from startrack.io._track_csv import track_csv_writer
from startrack.io._truth_files import write_with_sidecar
from startrack.io._wcs import write_wcs

RNG = np.random.default_rng(5)
NOISE16 = RNG.integers(0, 65536, size=(64, 64)).astype(np.uint16)


@contextmanager
def file_size_limit(n_bytes: int):
    """Writes past ``n_bytes`` fail with EFBIG (a full disk) inside this block."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (n_bytes, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


def _names(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


WRITERS = {
    "png": lambda path: write_png(path, NOISE16),
    "tif": lambda path: write_tiff(path, NOISE16),
    "fits": lambda path: write_fits(path, NOISE16),
    "csv": lambda path: write_output(path, "x,y\n" + "1.0,2.0\n" * 4000),
}


@pytest.mark.parametrize("suffix", sorted(WRITERS))
def test_a_full_disk_keeps_the_old_file_leaves_no_temporary_and_names_the_target(tmp_path, suffix):
    """Before: the message was the OS error on the temporary file or a bare errno text; now it names
    the target and says nothing changed (the old content and folder listing are checked too)."""
    target = tmp_path / f"out.{suffix}"
    target.write_bytes(b"old content")
    with file_size_limit(4096), pytest.raises(OutputError) as info:
        WRITERS[suffix](target)
    assert target.read_bytes() == b"old content"
    assert _names(tmp_path) == [target.name]
    message = str(info.value)
    assert message.startswith(f"cannot write {target}:") and "nothing was changed" in message
    assert ".tmp" not in message


def test_a_long_file_name_is_written(tmp_path):
    """Before: the temporary name (target name + 38 characters) went past the 255-byte limit and the
    error named the temporary file ("File name too long: '.aaa....tmp'")."""
    target = tmp_path / ("a" * 240 + ".png")
    write_png(target, NOISE16)
    np.testing.assert_array_equal(read_image(target).data, NOISE16)
    assert _names(tmp_path) == [target.name]


def test_a_fifo_is_written_through_not_replaced(tmp_path):
    """Before: the FIFO was replaced by a regular file (exit 0) and the reader got nothing."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    write_output(fifo, "a,b\n1,2\n")
    reader.join(timeout=10)
    assert received == [b"a,b\n1,2\n"]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_a_link_to_a_device_is_written_through_and_a_link_to_a_file_is_kept(tmp_path):
    """Before: both links were replaced by regular files."""
    to_null = tmp_path / "null.fits"
    to_null.symlink_to("/dev/null")
    write_fits(to_null, NOISE16)
    assert to_null.is_symlink() and stat.S_ISCHR(os.stat(to_null).st_mode)
    real = tmp_path / "real.png"
    real.write_bytes(b"old")
    link = tmp_path / "link.png"
    link.symlink_to(real.name)
    write_png(link, NOISE16)
    assert link.is_symlink()
    np.testing.assert_array_equal(read_image(real).data, NOISE16)
    assert _names(tmp_path) == ["link.png", "null.fits", "real.png"]


def test_standard_output_takes_a_csv(capsys):
    """Before: ``-`` was taken as a file named "-"."""
    with track_csv_writer("-") as write:
        write(["0", "frame.fits"] + [""] * 17)
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("frame,file,t_s") and out.splitlines()[1].startswith("0,frame.fits")


@pytest.mark.parametrize(("path", "match"), [("/dev/startrack-absent", "nothing is created under /dev"),
                                             ("", "must not be empty")])
def test_refused_targets(path, match):
    with pytest.raises(InvalidInputError, match=match):
        output_target(path)


def test_an_input_is_never_an_output(tmp_path):
    """Before: ``solve img.fits --wcs img.fits`` turned the image into a 5,760-byte header."""
    image = tmp_path / "img.fits"
    write_fits(image, NOISE16)
    alias = tmp_path / "alias.fits"
    alias.symlink_to(image.name)
    before = image.read_bytes()
    from scipy.spatial.transform import Rotation

    from startrack.camera import Camera

    camera = Camera.from_fov(64, 64, 10.0)
    with protect_inputs():
        read_image(image)
        for target in (image, alias):
            with pytest.raises(InvalidInputError, match="one of the inputs"):
                write_wcs(target, Rotation.identity(), camera)
    with pytest.raises(InvalidInputError, match="one of the inputs"):
        write_png(alias, NOISE16, inputs=[image])
    assert image.read_bytes() == before
    note_input(image)  # outside protect_inputs: no effect
    write_wcs(tmp_path / "out.wcs", Rotation.identity(), camera)


def test_an_image_and_its_sidecar_are_replaced_together_or_not_at_all(tmp_path):
    """Before: when the sidecar write failed, the old image was deleted and the old sidecar stayed."""
    image, sidecar = tmp_path / "pair.png", tmp_path / "pair.truth.json"
    image.write_bytes(b"old image")
    sidecar.write_text("old sidecar")
    with file_size_limit(2048), pytest.raises(OutputError, match="pair"):
        write_with_sidecar(image, b"new image", json.dumps({"stars": list(range(2000))}))
    assert image.read_bytes() == b"old image" and sidecar.read_text() == "old sidecar"
    assert _names(tmp_path) == ["pair.png", "pair.truth.json"]
    write_with_sidecar(image, b"new image", "{}")
    assert image.read_bytes() == b"new image" and sidecar.read_text() == "{}"


def test_a_folder_in_the_way_of_the_sidecar_stops_the_pair_before_anything_is_written(tmp_path):
    image = tmp_path / "pair.png"
    image.write_bytes(b"old image")
    (tmp_path / "pair.truth.json").mkdir()
    with pytest.raises(InvalidInputError, match="is a folder"):
        write_with_sidecar(image, b"new image", "{}")
    assert image.read_bytes() == b"old image"


def test_a_failing_writer_in_a_group_keeps_every_old_file(tmp_path):
    targets = [tmp_path / "a.txt", tmp_path / "b.txt"]
    for t in targets:
        t.write_text("old")
    with pytest.raises(RuntimeError, match="writer failed"), atomic_group(targets) as tmps:
        tmps[0].write_text("new")
        raise RuntimeError("writer failed")
    assert [t.read_text() for t in targets] == ["old", "old"]
    assert _names(tmp_path) == ["a.txt", "b.txt"]


def test_an_interrupted_stream_keeps_the_old_csv(tmp_path):
    target = tmp_path / "track.csv"
    target.write_text("old")
    with pytest.raises(KeyboardInterrupt), open_output(target) as fh:
        fh.write("frame,file\n0,a.fits\n")
        raise KeyboardInterrupt
    assert target.read_text() == "old" and _names(tmp_path) == ["track.csv"]


def test_a_dead_writers_temporary_file_is_removed_by_the_next_write(tmp_path):
    """Before: a kill during a write left ``.NAME.RANDOM.tmp`` files behind for good."""
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True)
    stale = tmp_path / f".out.csv.{int(dead.stdout)}.0123456789ab.tmp"
    stale.write_text("half")
    live = tmp_path / f".out.csv.{os.getpid()}.ba9876543210.tmp"
    live.write_text("mine")
    write_output(tmp_path / "out.csv", "x\n")
    assert _names(tmp_path) == [live.name, "out.csv"]
    assert remove_stale_temps(tmp_path) == 0
