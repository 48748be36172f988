"""Caches that heal (docs/io.md, "Caches"): content checked on load, rebuilt when wrong, stale
temporary files removed, an unwritable folder means no cache and one warning, numba's cache in
startrack's folder and a damaged one cleared."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from startrack import cache, numba_cache
from startrack.errors import CacheWarning

ARRAYS = {"a": np.arange(12.0).reshape(3, 4), "b": np.array([3, 1, 2], dtype=np.int32)}


@pytest.fixture
def folder(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    return tmp_path


def _builder(calls: list):
    def build():
        calls.append(1)
        return ARRAYS
    return build


def _rewrite(path: Path, arrays: dict, meta: dict) -> None:
    with open(path, "wb") as fh:
        np.savez(fh, __meta__=np.array(json.dumps(meta)), **arrays)


def test_a_well_formed_file_missing_an_array_is_rebuilt(folder):
    """Before: the file passed (its zip CRCs were fine) and the loader's ``arrays[...]`` raised a
    KeyError in every later run."""
    calls = []
    cache.load_or_build("t", 1, {"p": 1}, _builder(calls))
    (path,) = folder.glob("t-*.npz")
    meta = json.loads(str(np.load(path)["__meta__"]))
    _rewrite(path, {"a": ARRAYS["a"]}, meta)
    assert cache.load("t", 1, {"p": 1}) is None
    arrays = cache.load_or_build("t", 1, {"p": 1}, _builder(calls))
    assert calls == [1, 1] and set(arrays) == {"a", "b"}
    assert set(cache.load("t", 1, {"p": 1})) == {"a", "b"}


@pytest.mark.parametrize("change", ["values", "dtype", "format 1"])
def test_a_file_whose_arrays_were_replaced_or_of_the_old_layout_is_rebuilt(folder, change):
    cache.save("t", 1, {}, ARRAYS)
    (path,) = folder.glob("t-*.npz")
    meta = json.loads(str(np.load(path)["__meta__"]))
    arrays = dict(ARRAYS)
    if change == "values":
        arrays["a"] = arrays["a"] + 1.0
    elif change == "dtype":
        arrays["b"] = arrays["b"].astype(np.int64)
    else:
        meta = {k: meta[k] for k in ("key", "version", "kind")}
    assert cache.is_current("t", 1, {})
    _rewrite(path, arrays, meta)
    assert cache.load("t", 1, {}) is None
    assert cache.is_current("t", 1, {}) == (change != "format 1")


def test_an_unwritable_cache_folder_means_no_cache_and_one_warning(tmp_path, monkeypatch):
    """Before: the CacheError threw the freshly built table away (the command failed)."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv(cache.ENV_VAR, str(blocker / "cache"))
    calls = []
    with pytest.warns(CacheWarning, match="cannot write the cache file .*going on without the cache") as caught:
        first = cache.load_or_build("t", 1, {}, _builder(calls))
        second = cache.load_or_build("t", 2, {}, _builder(calls))
    assert len(caught) == 1 and calls == [1, 1]
    np.testing.assert_array_equal(first["a"], ARRAYS["a"])
    np.testing.assert_array_equal(second["b"], ARRAYS["b"])
    assert ".tmp" not in str(caught[0].message)


def test_temporary_files_of_dead_writers_are_removed(folder):
    """Before: a kill during a write left ``.tmp`` files in the cache folder for good."""
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True)
    stale = folder / f".t-0123456789abcdef.npz.{int(dead.stdout)}.0123456789ab.tmp"
    old_layout = folder / "t-0123456789abcdefk3j2h1.tmp"
    fresh_old_layout = folder / "t-fedcba9876543210q9w8e7.tmp"
    for path in (stale, old_layout, fresh_old_layout):
        path.write_bytes(b"half a table")
    an_hour_ago = time.time() - 2 * numba_cache.STALE_TEMP_S
    os.utime(old_layout, (an_hour_ago, an_hour_ago))
    cache.save("t", 1, {}, ARRAYS)
    assert sorted(p.name for p in folder.iterdir()) == sorted([fresh_old_layout.name, *(p.name for p in
                                                                                        folder.glob("t-*.npz"))])


_KERNEL = """
from numba import njit

@njit(cache=True)
def twice(x):
    return 2.0 * x
"""


def _run_kernel(tmp_path: Path) -> subprocess.CompletedProcess:
    code = ("import sys; sys.path.insert(0, sys.argv[1])\n"
            "from startrack import numba_cache\n"
            "from startrack.cache import cache_dir\n"
            "numba_cache.heal(numba_cache.configured_dir())\n"
            "import kernel; print(kernel.twice(21.0))\n")
    env = {k: v for k, v in os.environ.items() if k != numba_cache.NUMBA_ENV_VAR}
    env[cache.ENV_VAR] = str(tmp_path / "cache")
    return subprocess.run([sys.executable, "-c", code, str(tmp_path / "src")], capture_output=True, text=True,
                          env=env, timeout=300)


def test_numba_caches_in_startracks_folder_and_a_damaged_index_is_cleared(tmp_path):
    """Before: numba wrote beside the package, and a damaged index file made every later run end in
    ``_pickle.UnpicklingError`` (exit 1)."""
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "kernel.py").write_text(textwrap.dedent(_KERNEL))
    first = _run_kernel(tmp_path)
    assert first.stdout.strip() == "42.0", first.stderr
    indexes = list((tmp_path / "cache" / "numba").rglob("*.nbi"))
    data = list((tmp_path / "cache" / "numba").rglob("*.nbc"))
    assert len(indexes) == 1 and len(data) == 1
    assert not list((tmp_path / "src").rglob("*.nbi"))
    indexes[0].write_bytes(indexes[0].read_bytes()[:40])
    data[0].write_bytes(data[0].read_bytes()[:-100])
    again = _run_kernel(tmp_path)
    assert again.returncode == 0 and again.stdout.strip() == "42.0", again.stderr
    assert len(list((tmp_path / "cache" / "numba").rglob("*.nbi"))) == 1


def test_heal_keeps_whole_files_and_removes_damaged_and_stale_ones(tmp_path):
    import pickle

    good_index = tmp_path / "f-1.py311.nbi"
    with open(good_index, "wb") as fh:
        pickle.dump("0.68.1", fh)
        fh.write(pickle.dumps((1.0, {"sig": "f-1.py311.1.nbc"})))
    good_data = tmp_path / "f-1.py311.1.nbc"
    good_data.write_bytes(pickle.dumps(("code", b"\x00" * 64)))
    bad_data = tmp_path / "g-2.py311.1.nbc"
    bad_data.write_bytes(pickle.dumps(("code", b"\x00" * 64))[:-5])
    stale = tmp_path / "g-2.py311.nbi.tmp.0123456789abcdef"
    stale.write_bytes(b"")
    old = time.time() - 2 * numba_cache.STALE_TEMP_S
    os.utime(stale, (old, old))
    removed = numba_cache.heal(tmp_path)
    assert sorted(p.name for p in removed) == sorted([bad_data.name, stale.name])
    assert good_index.exists() and good_data.exists()
