"""A folder's images in the order their names number them: before, plain name order put
frame_10 before frame_2, and `startrack track` gave frames without padded numbers wrong times."""

from __future__ import annotations

from pathlib import Path

from startrack.cli._batch import expand_inputs
from startrack.io import in_name_order


def test_numbers_in_names_are_compared_as_numbers():
    names = ["frame_10.png", "frame_2.png", "Frame_1.png", "frame_02.png", "a.png", "frame_2b.png"]
    assert [p.name for p in in_name_order([Path(n) for n in names])] == \
        ["a.png", "Frame_1.png", "frame_02.png", "frame_2.png", "frame_2b.png", "frame_10.png"]


def test_a_batch_folder_lists_its_images_in_that_order(tmp_path):
    for n in (1, 2, 10, 11, 100):
        (tmp_path / f"img{n}.jpg").write_bytes(b"")
    (tmp_path / "notes.txt").write_text("")
    assert [p.name for p in expand_inputs([tmp_path])] == ["img1.jpg", "img2.jpg", "img10.jpg", "img11.jpg",
                                                           "img100.jpg"]
