"""The package and its subpackages import their public names on first use (PEP 562): every name
of today's ``__all__`` still imports, to the object its module defines, and ``import startrack``
or a command's module loads none of the heavy libraries it does not call."""

from __future__ import annotations

import importlib
import subprocess
import sys
import types

import pytest

import startrack

LAZY_PACKAGES = ("startrack", "startrack.adcs", "startrack.catalog", "startrack.detect", "startrack.identify",
                 "startrack.multihead", "startrack.rate", "startrack.simulate", "startrack.track")

TOP_LEVEL_NAMES = ["AttitudeSolution", "Camera", "CameraRig", "Detections", "RigHead", "RigSolution",
                   "StarMatches", "Status", "__version__", "get_preset", "solve_image", "solve_rig", "solve_stars"]


def test_top_level_all_is_unchanged():
    assert sorted(startrack.__all__) == sorted(TOP_LEVEL_NAMES)


@pytest.mark.parametrize("name", TOP_LEVEL_NAMES)
def test_every_top_level_name_imports(name):
    namespace: dict = {}
    exec(f"from startrack import {name}", namespace)  # the statement users write
    assert namespace[name] is getattr(startrack, name)


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_exports_are_the_defining_modules_objects(package):
    module = importlib.import_module(package)
    for name, origin in module._EXPORTS.items():
        value = getattr(module, name)
        assert not isinstance(value, types.ModuleType), f"{package}.{name} is shadowed by a submodule"
        assert value is getattr(importlib.import_module(origin, package), name)
    assert set(module.__all__) <= set(module._EXPORTS) | {"__version__"}
    assert set(module.__all__) <= set(dir(module))


def test_star_import_gives_all():
    namespace: dict = {}
    exec("from startrack.detect import *", namespace)
    assert {"StarDetector", "detect", "to_single_channel"} <= set(namespace)


def test_submodule_as_attribute_and_unknown_name():
    import startrack.catalog as catalog

    assert catalog._cone is importlib.import_module("startrack.catalog._cone")
    with pytest.raises(AttributeError, match="'startrack.catalog' has no attribute 'no_such_name'"):
        _ = catalog.no_such_name
    with pytest.raises(ImportError, match="no_such_name"):
        exec("from startrack import no_such_name", {})


def _loaded_in_fresh_process(statement: str) -> set[str]:
    """Top-level packages in sys.modules after ``statement`` in a new interpreter."""
    code = f"import sys; {statement}; print(' '.join(sorted({{m.split('.')[0] for m in sys.modules}})))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    return set(out.stdout.split())


def test_import_startrack_loads_no_numerical_library():
    loaded = _loaded_in_fresh_process("import startrack")
    assert not loaded & {"numpy", "scipy", "astropy", "numba", "PIL", "matplotlib"}


@pytest.mark.parametrize("module", ["startrack.cli._solve_cmd", "startrack.cli._detect_cmd",
                                    "startrack.cli._solve_stars_cmd"])
def test_image_commands_do_not_load_astropy_or_matplotlib(module):
    loaded = _loaded_in_fresh_process(f"import {module}")
    assert not loaded & {"astropy", "matplotlib", "erfa"}


def test_command_line_loads_only_the_chosen_command():
    code = ("import sys, startrack.cli._main as m; m.main(['--version']); "
            "print(sorted(n for n in sys.modules if n.startswith('startrack.cli.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert "startrack.cli._main" in out.stdout
    assert "_cmd" not in out.stdout


def test_default_detection_does_not_load_scipy_ndimage():
    # scipy.ndimage costs about 30 ms of a command's start; only optional stages (denoising, the
    # region-grow grouping, tiles without sky) use it, and they import it when they run
    code = ("import sys, numpy as np; from startrack.detect import StarDetector; "
            "StarDetector().detect(np.random.default_rng(0).normal(100, 3, (64, 64)).astype(np.uint16)); "
            "print('scipy.ndimage' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.split()[-1] == "False"


@pytest.mark.parametrize("module", ["startrack.cli._solve_stars_cmd", "startrack.cli._campaign_cmd",
                                    "startrack.cli._availability_cmd"])
def test_commands_without_images_do_not_load_pillow(module):
    """A command that reads no image (a star list, a campaign spec) loads neither the image reader
    nor Pillow: the helpers they share with the image commands import the reader's types only for
    the type checker."""
    loaded = _loaded_in_fresh_process(f"import {module}")
    assert "PIL" not in loaded
