"""Cache files mapped, not read (docs/io.md, "Caches"): the arrays of a file :func:`cache.save`
wrote are views of the mapped file, aligned for their dtypes; a file of the unaligned layout
(``np.savez``) is read, checked and written again aligned; the CRCs are computed once per file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from startrack import cache

ARRAYS = {"keys": np.arange(1000, dtype=np.int64) * 3, "vectors": np.linspace(0.0, 1.0, 30).reshape(10, 3),
          "stars": np.arange(20, dtype=np.uint16).reshape(5, 4), "fortran": np.asfortranarray(np.eye(3)[:, :2]),
          "empty": np.zeros((0, 3)), "scalar": np.array(2.5)}


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    return tmp_path


def _same(loaded: dict) -> None:
    assert set(loaded) == set(ARRAYS)
    for name, array in ARRAYS.items():
        assert loaded[name].dtype == array.dtype and loaded[name].shape == array.shape, name
        np.testing.assert_array_equal(loaded[name], array)


def test_saved_arrays_load_as_aligned_views_of_the_mapped_file(folder):
    path = cache.save("t", 1, {}, ARRAYS)
    with np.load(path) as npz:  # still an ordinary .npz for numpy
        np.testing.assert_array_equal(npz["keys"], ARRAYS["keys"])
    loaded = cache.load("t", 1, {})
    _same(loaded)
    for name in ("keys", "vectors", "stars", "fortran"):
        assert not loaded[name].flags.owndata and loaded[name].flags.aligned, name
    assert loaded["fortran"].flags.f_contiguous
    loaded["keys"][0] = -1  # copy-on-write: this process only
    assert cache.load("t", 1, {})["keys"][0] == 0


def test_a_file_of_the_unaligned_layout_is_read_checked_and_written_again_aligned(folder):
    path = cache.save("t", 1, {}, ARRAYS)
    meta = json.loads(str(np.load(path)["__meta__"]))
    with open(path, "wb") as fh:  # as the cache wrote it before (np.savez: members at any offset)
        np.savez(fh, __meta__=np.array(json.dumps(meta)), **ARRAYS)
    _same(cache.load("t", 1, {}))
    again = cache.load("t", 1, {})
    _same(again)
    assert not again["keys"].flags.owndata


def test_crcs_are_checked_once_per_file_and_again_when_it_changes(folder):
    path = cache.save("t", 1, {}, ARRAYS)
    record = folder / cache.VERIFIED_NAME
    assert not record.exists()  # a file is trusted only after a load has checked it
    cache.load("t", 1, {})
    assert path.name in json.loads(record.read_text())
    meta = json.loads(str(np.load(path)["__meta__"]))
    with open(path, "wb") as fh:  # same manifest, other values: the CRCs must catch it
        np.savez(fh, __meta__=np.array(json.dumps(meta)), **{**ARRAYS, "keys": ARRAYS["keys"] + 1})
    assert cache.load("t", 1, {}) is None


def test_a_recorded_file_that_lost_an_array_is_refused(folder):
    path = cache.save("t", 1, {}, ARRAYS)
    cache.load("t", 1, {})
    record = json.loads((folder / cache.VERIFIED_NAME).read_text())
    meta = json.loads(str(np.load(path)["__meta__"]))
    with open(path, "wb") as fh:
        np.savez(fh, __meta__=np.array(json.dumps(meta)), **{k: v for k, v in ARRAYS.items() if k != "stars"})
    stamp = cache._stamp(path)
    (folder / cache.VERIFIED_NAME).write_text(json.dumps({**record, path.name: stamp}))  # even if trusted
    assert cache.load("t", 1, {}) is None
