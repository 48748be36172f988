"""A numba cache folder that cannot be written sends numba to a private temporary folder, with one
warning, instead of ending in "cannot cache function ...: no locator available" (or, as root, of
numba caching into the package's own ``__pycache__``)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import pytest

import startrack
from startrack import numba_cache
from startrack.errors import CacheWarning

PACKAGE = Path(startrack.__file__).resolve().parent


@pytest.fixture
def fresh(monkeypatch: pytest.MonkeyPatch) -> None:
    """numba_cache as in a new process with no NUMBA_CACHE_DIR (numba's config restored after)."""
    for name in ("_CONFIGURED", "_CHOSEN", "_UNWRITABLE"):
        monkeypatch.setattr(numba_cache, name, [])
    monkeypatch.delenv(numba_cache.NUMBA_ENV_VAR, raising=False)
    if "numba" in sys.modules:
        from numba.core import config

        monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)  # type: ignore[attr-defined]


def _under_a_file(tmp_path: Path) -> Path:
    """A folder that cannot be created, even by root."""
    (tmp_path / "file").write_text("")
    return tmp_path / "file" / "cache"


def _chosen_with_one_warning() -> tuple[Path, str]:
    with pytest.warns(CacheWarning) as record:
        chosen = numba_cache.configured_dir()
    assert len(record) == 1 and chosen is not None
    return chosen, str(record[0].message)


def test_an_unwritable_folder_means_a_private_temporary_folder_and_one_warning(tmp_path, fresh):
    root = _under_a_file(tmp_path)
    assert numba_cache.configure(root) == root / "numba"  # no file touched yet
    chosen, message = _chosen_with_one_warning()
    try:
        assert chosen.is_dir() and chosen.name.startswith(numba_cache.PRIVATE_PREFIX)
        assert numba_cache._write_error(chosen) is None and not list(chosen.iterdir())
        assert PACKAGE not in chosen.resolve().parents and tmp_path not in chosen.parents
        assert os.environ[numba_cache.NUMBA_ENV_VAR] == str(chosen)
        if "numba" in sys.modules:
            from numba.core import config

            assert config.CACHE_DIR == str(chosen)
        assert str(root / "numba") in message and "not kept for later runs" in message
        assert "STARTRACK_CACHE_DIR" in message and "NUMBA_CACHE_DIR" in message
        assert not numba_cache.keeps_compiled_code()
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # checked and warned once per process
            assert numba_cache.configured_dir() == chosen
        numba_cache._remove_private(chosen, os.getpid() + 1)  # not the process that made it
        assert chosen.is_dir()
    finally:
        numba_cache._remove_private(chosen, os.getpid())
    assert not chosen.exists()


def test_a_writable_folder_is_used_and_the_test_file_removed(tmp_path, fresh):
    folder = numba_cache.configure(tmp_path / "cache")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert numba_cache.configured_dir() == folder == tmp_path / "cache" / "numba"
    assert folder.is_dir() and not list(folder.iterdir())
    assert numba_cache.keeps_compiled_code()


def test_the_users_own_numba_folder_is_respected(tmp_path, fresh, monkeypatch):
    monkeypatch.setenv(numba_cache.NUMBA_ENV_VAR, str(tmp_path / "mine"))
    assert numba_cache.configure(tmp_path / "cache") is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert numba_cache.configured_dir() is None
    assert os.environ[numba_cache.NUMBA_ENV_VAR] == str(tmp_path / "mine")
    assert not (tmp_path / "cache").exists()


def test_the_users_own_unwritable_numba_folder_is_replaced_too(tmp_path, fresh, monkeypatch):
    mine = _under_a_file(tmp_path)
    monkeypatch.setenv(numba_cache.NUMBA_ENV_VAR, str(mine))
    assert numba_cache.configure(tmp_path / "cache") is None
    chosen, message = _chosen_with_one_warning()
    numba_cache._remove_private(chosen, os.getpid())
    assert str(mine) in message and "NUMBA_CACHE_DIR" in message and "STARTRACK_CACHE_DIR" not in message


_KERNEL = """
from numba import njit

@njit(cache=True)
def twice(x):
    return 2.0 * x
"""


def test_a_kernel_compiles_with_an_unwritable_cache_folder(tmp_path):
    """Before: RuntimeError "cannot cache function 'twice': no locator available" (exit 1) as a
    user, and as root numba cached into ``__pycache__`` beside the kernel's source."""
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "kernel.py").write_text(textwrap.dedent(_KERNEL))
    code = ("import sys; sys.path.insert(0, sys.argv[1])\n"
            "from startrack import cache, numba_cache\n"
            "numba_cache.heal(numba_cache.configured_dir())\n"
            "import kernel; print(kernel.twice(21.0))\n")
    env = {k: v for k, v in os.environ.items() if k != numba_cache.NUMBA_ENV_VAR}
    env["STARTRACK_CACHE_DIR"] = str(_under_a_file(tmp_path))
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "src")], capture_output=True, text=True,
                         env=env, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == "42.0", run.stderr
    assert run.stderr.count("cannot write the numba cache folder") == 1, run.stderr
    assert not list((tmp_path / "src").rglob("*.nb[ic]"))
    private = Path(run.stderr.split("a temporary folder (", 1)[1].split(")", 1)[0])
    assert private.name.startswith(numba_cache.PRIVATE_PREFIX) and not private.exists()  # removed at exit
