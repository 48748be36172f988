"""read_json_file: a user's JSON file, or one InvalidInputError naming what it was for and the problem."""

from __future__ import annotations

import pytest

from startrack.errors import InvalidInputError
from startrack.io import read_json_file


def test_reads_utf8_whatever_the_locale(tmp_path):
    path = tmp_path / "site.json"
    path.write_bytes('{"name": "Zürich", "height_m": 408}'.encode())
    assert read_json_file(path, "site file") == {"name": "Zürich", "height_m": 408}


@pytest.mark.parametrize("content, words", [
    (b"SIMPLE  =  T\x80\x81", "rig file {p} is not JSON text: byte 12 is not UTF-8 (is it an image"),
    (b"{'single': 'quotes'}", "rig file {p} is not valid JSON: Expecting property name"),
    (None, "cannot read rig file {p}: No such file or directory"),
    # ValueError and RecursionError of Python's decoder, outside JSONDecodeError: exit 3 in the commands
    (b'{"latency_s": ' + b"9" * 5000 + b"}", "rig file {p} holds an integer of more than"),
    (b"[" * 100_000 + b"]" * 100_000, "rig file {p} nests arrays or objects too deeply"),
])
def test_a_file_that_is_not_json_is_named_with_its_problem(tmp_path, content, words):
    path = tmp_path / "rig.json"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(InvalidInputError) as info:
        read_json_file(path, "rig file")
    assert words.format(p=path) in str(info.value)
