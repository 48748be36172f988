"""The public surface: every name of every package's ``__all__`` imports and has a docstring,
``docs/api.md`` is what ``scripts/api_doc.py`` prints now, and no module of one subpackage imports
another subpackage's module past its ``__init__`` except the imports listed here with a reason.

The list of imports past an ``__init__`` is a ratchet: a new one fails (import the name from the
package, adding it to the package's ``__all__`` if it is new to the public surface), and so does
an entry that is gone (delete it here). Routing through a package costs no import time: a
package's ``__init__`` runs whenever one of its modules is imported, and the lazy ones (PEP 562)
load only the module a name comes from.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import types
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


def _api_doc() -> types.ModuleType:
    spec = importlib.util.spec_from_file_location("api_doc", ROOT / "scripts" / "api_doc.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


API_DOC = _api_doc()
PACKAGES = [package for _, packages in API_DOC.STAGES for package in packages]

UNDOCUMENTED = frozenset("""
    startrack.simulate.MU_EARTH_KM3_S2
    startrack.simulate.PASSBANDS
    startrack.simulate.R_EARTH_KM
    startrack.simulate.R_MOON_KM
    startrack.simulate.R_SUN_KM
    startrack.simulate.SENSOR_PRESETS
    startrack.detect.CENTROIDERS
    startrack.detect.THRESHOLDS
    startrack.identify.DB_KIND
    startrack.calibrate.DEFAULT_FIT
    startrack.calibrate.get_site
    startrack.adcs.FEEDBACKS
    startrack.adcs.FIELDS
    startrack.adcs.HORIZONS
    startrack.adcs.METRIC_KEYS
    startrack.adcs.PLANTS
    startrack.analysis.TOLERANCE_PIXELS
    startrack.io.COLUMNS
    startrack.io.ENV_VAR
    startrack.io.SUPPORTED_FORMATS
    startrack.web.DEFAULT_MAX_QUEUED
    startrack.web.DEFAULT_MAX_UPLOAD_MB
    startrack.web.DEFAULT_PORT
    startrack.web.DEFAULT_TIME_LIMIT_S
    startrack.cli.SUBCOMMANDS
""".split())
"""Public names whose docstring is still to be written in their defining module (owned by other
engineers while issue 21 is worked on): constants want an attribute docstring, the string right
after the assignment. ``__version__`` is exempt."""

IMPORTS_PAST_INIT = {
    "startrack.multihead._availability startrack.analysis._availability":
        "the rig's star availability counts each head's stars with the single-camera chunk counter "
        "(_count_chunk, CHUNK): one implementation of the count, which is not an analysis API",
}
"""``"importer target"`` -> why ``importer`` imports ``target`` (a private module of another
subpackage) rather than a name of that subpackage. Before the modules of the subpackages became
private (2026-12-02) there were 215 such pairs; routing every other import through the package's
public names left this one."""


def test_every_package_is_on_the_api_page():
    packages = {".".join(p.relative_to(SRC).parts[:-1]) for p in (SRC / "startrack").rglob("__init__.py")}
    assert packages == set(PACKAGES)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_name_in_all_exists(package):
    module = importlib.import_module(package)
    assert len(module.__all__) == len(set(module.__all__)), f"{package}.__all__ repeats a name"
    exports = getattr(module, "_EXPORTS", {})
    for name in module.__all__:
        value = getattr(module, name)  # imports it
        assert not isinstance(value, types.ModuleType), f"{package}.{name} is a module, not a public name"
        if name in exports:
            assert value is getattr(importlib.import_module(exports[name], package), name)
    namespace: dict = {}
    exec(f"from {package} import *", namespace)  # the statement users write
    assert set(module.__all__) <= set(namespace)


def test_every_public_name_has_a_docstring():
    missing = {f"{p.package}.{p.name}" for package in PACKAGES for p in API_DOC.public_names(package)
               if not p.summary and p.name != "__version__"}
    assert not missing - UNDOCUMENTED, "public names without a docstring"
    assert not UNDOCUMENTED - missing, "documented now: delete them from UNDOCUMENTED"


def test_api_page_is_what_the_script_prints():
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert page == API_DOC.render(), "docs/api.md is stale: run python scripts/api_doc.py > docs/api.md"


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@cache
def _is_package(module: str) -> bool:
    return SRC.joinpath(*module.split("."), "__init__.py").is_file()


@cache
def _is_module(module: str) -> bool:
    return _is_package(module) or SRC.joinpath(*module.split(".")).with_suffix(".py").is_file()


def _statements(body: list[ast.stmt]):
    """Every statement of ``body`` and of the blocks inside it (imports are statements; skipping the
    expressions keeps the scan fast)."""
    for node in body:
        yield node
        for block in ("body", "orelse", "finalbody", "handlers", "cases"):
            inner = getattr(node, block, None)
            if isinstance(inner, list):
                yield from _statements(inner)


def _targets(path: Path):
    """The modules ``path`` imports (``from package import module`` counts as ``package.module``)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in _statements(ast.parse(path.read_text(encoding="utf-8")).body):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                head = package.split(".")[: package.count(".") + 2 - node.level]
                base = ".".join(head + ([node.module] if node.module else []))
            names = [f"{base}.{alias.name}" for alias in node.names]
            modules = [n for n in names if _is_module(n)]
            yield from modules
            if len(modules) < len(names):
                yield base


def imports_past_init() -> set[str]:
    """``"importer target"`` for every module of startrack importing a module (not a package) of a
    subpackage other than its own."""
    found = set()
    for path in sorted((SRC / "startrack").rglob("*.py")):
        importer = _module_name(path)
        top = ".".join(importer.split(".")[:2])
        for target in _targets(path):
            parts = target.split(".")
            subpackage = ".".join(parts[:2])
            if parts[0] != "startrack" or subpackage == top or not _is_package(subpackage) or _is_package(target):
                continue
            found.add(f"{importer} {target}")
    return found


def test_no_module_imports_past_another_subpackages_init():
    found = imports_past_init()
    new = sorted(found - set(IMPORTS_PAST_INIT))
    gone = sorted(set(IMPORTS_PAST_INIT) - found)
    assert not new, f"import these from the subpackage (add the name to its __all__): {new}"
    assert not gone, f"no longer imported past the package's __init__: delete from IMPORTS_PAST_INIT: {gone}"
    assert all(IMPORTS_PAST_INIT.values())


def test_every_module_of_a_subpackage_is_private():
    public = sorted(str(p.relative_to(SRC)) for p in (SRC / "startrack").rglob("*.py")
                    if p.parent != SRC / "startrack" and not p.name.startswith("_"))
    assert not public, "a subpackage's __init__ is its contract: give these modules a leading underscore"
