"""startrack.numba_cache.heal remembers the files it found whole (by size and modification time)
and reads only new or changed ones; a file damaged after it was recorded is still removed."""

from __future__ import annotations

import json
import os
import pickle
from pathlib import Path

from startrack import numba_cache


def _cache(folder: Path) -> tuple[Path, Path]:
    sub = folder / "identify_0123"
    sub.mkdir(parents=True)
    index = sub / "f-1.py311.nbi"
    with open(index, "wb") as fh:
        pickle.dump("0.68.1", fh)
        fh.write(pickle.dumps((1.0, {"sig": "f-1.py311.1.nbc"})))
    data = sub / "f-1.py311.1.nbc"
    data.write_bytes(pickle.dumps(("code", b"\x00" * 64)))
    return index, data


def _heal(folder: Path) -> list[Path]:
    numba_cache._HEALED.discard(folder)  # a new process, as far as heal is concerned
    return numba_cache.heal(folder)


def test_whole_files_are_recorded_and_not_read_again(tmp_path, monkeypatch):
    index, data = _cache(tmp_path)
    assert _heal(tmp_path) == []
    record = json.loads((tmp_path / numba_cache.CHECKED_NAME).read_text())
    assert sorted(record) == ["identify_0123/f-1.py311.1.nbc", "identify_0123/f-1.py311.nbi"]
    assert record["identify_0123/f-1.py311.nbi"] == [index.stat().st_size, index.stat().st_mtime_ns]
    read = []
    monkeypatch.setattr(numba_cache, "_check", lambda path: read.append(path) or True)
    assert _heal(tmp_path) == [] and read == []


def test_a_file_damaged_after_it_was_recorded_is_removed(tmp_path):
    index, data = _cache(tmp_path)
    _heal(tmp_path)
    data.write_bytes(data.read_bytes()[:-5])  # truncated: another size
    index.write_bytes(b"\x80\x04garbage")
    assert sorted(_heal(tmp_path)) == sorted([data, index])
    assert not data.exists() and not index.exists()
    assert json.loads((tmp_path / numba_cache.CHECKED_NAME).read_text()) == {}


def test_a_rewritten_file_of_the_same_size_is_read_again(tmp_path):
    index, data = _cache(tmp_path)
    _heal(tmp_path)
    whole = data.read_bytes()
    data.write_bytes(whole[:-1] + b"X")  # same size, STOP opcode gone
    stamp = data.stat()
    os.utime(data, ns=(stamp.st_atime_ns, stamp.st_mtime_ns + 1_000_000))
    assert _heal(tmp_path) == [data]


def test_an_unreadable_record_means_checking_everything(tmp_path):
    index, data = _cache(tmp_path)
    (tmp_path / numba_cache.CHECKED_NAME).write_text("{not json")
    data.write_bytes(data.read_bytes()[:-5])
    assert _heal(tmp_path) == [data]
    assert list(json.loads((tmp_path / numba_cache.CHECKED_NAME).read_text())) == ["identify_0123/f-1.py311.nbi"]
