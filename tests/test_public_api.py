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

ROUTABLE = "to be routed through the package: the names it imports are in the package's __all__"
NOT_YET_PUBLIC = ("to be routed through the package once the name is public: a private helper, a module "
                  "imported as a whole, a function named as its module (field_stars, streak_rate, "
                  "repeatability: the submodule would shadow it in a lazy package) or a name "
                  "analysis.postprocess does not export yet")

IMPORTS_PAST_INIT = {line.strip(): ROUTABLE for line in """
    startrack.adcs.star_tracker_feedback startrack.simulate.sequence
    startrack.analysis.calibration_plots startrack.calibrate.lens_models
    startrack.analysis.calibration_plots startrack.calibrate.repeatability
    startrack.analysis.campaign.aggregate startrack.io.atomic
    startrack.analysis.campaign.levels._sunsat startrack.identify.match_groups
    startrack.analysis.campaign.levels._sunsat startrack.identify.pair_database
    startrack.analysis.campaign.levels.common startrack.identify.registry
    startrack.analysis.campaign.levels.groupmatch startrack.identify.match_groups
    startrack.analysis.campaign.levels.groupmatch startrack.identify.refine
    startrack.analysis.campaign.levels.image startrack.simulate.motion
    startrack.analysis.campaign.levels.photometry startrack.simulate.radiometry
    startrack.analysis.campaign.levels.prefilter startrack.detect.background
    startrack.analysis.campaign.levels.prefilter startrack.detect.pipeline
    startrack.analysis.campaign.levels.prefilter startrack.detect.smooth
    startrack.analysis.campaign.levels.rig startrack.multihead.exclusion
    startrack.analysis.campaign.levels.rig startrack.simulate.rig
    startrack.analysis.campaign.levels.rso startrack.rate.endpoints
    startrack.analysis.campaign.levels.rso startrack.rate.estimate
    startrack.analysis.campaign.levels.rso startrack.rate.rso
    startrack.analysis.campaign.levels.scene startrack.calibrate.apparent
    startrack.analysis.campaign.levels.scene startrack.simulate.radiometry
    startrack.analysis.campaign.levels.seqmatch startrack.identify.registry
    startrack.analysis.campaign.levels.seqmatch startrack.rate.from_attitudes
    startrack.analysis.campaign.levels.seqmatch startrack.track.relative
    startrack.analysis.campaign.levels.sequence startrack.track.tracker
    startrack.analysis.campaign.levels.smear startrack.detect.centroiders
    startrack.analysis.campaign.levels.smear startrack.rate.streak_detect
    startrack.analysis.campaign.levels.smearlimit startrack.simulate.radiometry
    startrack.analysis.campaign.levels.streak startrack.rate.endpoints
    startrack.analysis.campaign.levels.streak startrack.rate.streak_rate
    startrack.analysis.campaign.levels.streak_frames startrack.rate.streak_solve
    startrack.analysis.campaign.levels.streak_frames startrack.simulate.radiometry
    startrack.analysis.campaign.provenance startrack.identify.database
    startrack.analysis.campaign.provenance startrack.identify.registry
    startrack.analysis.campaign.report startrack.io.atomic
    startrack.analysis.campaign.rerun startrack.io.atomic
    startrack.analysis.campaign.rerun startrack.io.truth_files
    startrack.analysis.campaign.store startrack.io.atomic
    startrack.analysis.postprocess.core startrack.io.atomic
    startrack.analysis.postprocess.corrections startrack.calibrate.apparent
    startrack.analysis.postprocess.corrections startrack.calibrate.ground
    startrack.analysis.postprocess.figures startrack.calibrate.repeatability
    startrack.analysis.postprocess.ground startrack.calibrate.sites
    startrack.analysis.postprocess.magnitude startrack.detect.magnitude
    startrack.analysis.postprocess.records_io startrack.calibrate.ground
    startrack.analysis.postprocess.records_io startrack.calibrate.sites
    startrack.analysis.postprocess.records_io startrack.io.image
    startrack.analysis.postprocess.repeatability startrack.calibrate.ground
    startrack.analysis.records startrack.calibrate.sites
    startrack.analysis.records startrack.simulate.truth
    startrack.analysis.rso_passes startrack.simulate.orbits
    startrack.cache startrack.io.atomic
    startrack.calibrate.apparent startrack.catalog.star_catalog
    startrack.calibrate.ground_solve startrack.attitude.qmethod
    startrack.calibrate.sites startrack.io.atomic
    startrack.cli.adcs_cmd startrack.adcs.cubesat
    startrack.cli.adcs_cmd startrack.adcs.guidance
    startrack.cli.adcs_cmd startrack.adcs.loop
    startrack.cli.adcs_cmd startrack.adcs.metrics
    startrack.cli.adcs_cmd startrack.adcs.plots
    startrack.cli.adcs_cmd startrack.adcs.report
    startrack.cli.adcs_cmd startrack.adcs.scenario
    startrack.cli.adcs_cmd startrack.adcs.star_tracker_feedback
    startrack.cli.analyse_cmd startrack.analysis.postprocess.core
    startrack.cli.availability_cmd startrack.analysis.availability
    startrack.cli.availability_cmd startrack.analysis.plots
    startrack.cli.availability_cmd startrack.io.atomic
    startrack.cli.availability_cmd startrack.io.targets
    startrack.cli.availability_cmd startrack.multihead.availability
    startrack.cli.availability_cmd startrack.multihead.exclusion
    startrack.cli.batch startrack.io.atomic
    startrack.cli.batch startrack.io.image
    startrack.cli.batch startrack.io.targets
    startrack.cli.batch_solve startrack.io.solution_json
    startrack.cli.calibrate_cmd startrack.calibrate.bench
    startrack.cli.calibrate_cmd startrack.calibrate.stars
    startrack.cli.calibrate_cmd startrack.io.atomic
    startrack.cli.campaign_cmd startrack.analysis.campaign.params
    startrack.cli.campaign_cmd startrack.analysis.campaign.report
    startrack.cli.campaign_cmd startrack.analysis.campaign.rerun
    startrack.cli.campaign_cmd startrack.analysis.campaign.run
    startrack.cli.campaign_cmd startrack.analysis.campaign.shipped
    startrack.cli.campaign_cmd startrack.analysis.campaign.spec
    startrack.cli.campaign_cmd startrack.analysis.campaign.summary
    startrack.cli.common startrack.identify.registry
    startrack.cli.common startrack.io.limits
    startrack.cli.common startrack.io.solution_json
    startrack.cli.demo_cmd startrack.analysis.plots
    startrack.cli.demo_cmd startrack.io.solution_json
    startrack.cli.demo_cmd startrack.io.truth_files
    startrack.cli.detect_cmd startrack.detect.centroiders
    startrack.cli.detect_cmd startrack.detect.details
    startrack.cli.detect_cmd startrack.detect.detector
    startrack.cli.progress startrack.identify.database
    startrack.cli.progress startrack.identify.registry
    startrack.cli.rate_cmd startrack.rate.streak_detect
    startrack.cli.render_limits startrack.io.limits
    startrack.cli.run_context startrack.io.limits
    startrack.cli.run_context startrack.io.targets
    startrack.cli.simulate_cmd startrack.io.atomic
    startrack.cli.simulate_cmd startrack.io.fitsfile
    startrack.cli.simulate_cmd startrack.io.tiff
    startrack.cli.simulate_cmd startrack.io.truth_files
    startrack.cli.simulate_cmd startrack.io.writers
    startrack.cli.simulate_cmd startrack.multihead.exclusion
    startrack.cli.simulate_cmd startrack.simulate.rig
    startrack.cli.simulate_cmd startrack.simulate.split_fov
    startrack.cli.solve_cmd startrack.calibrate.ground_solve
    startrack.cli.solve_cmd startrack.calibrate.sites
    startrack.cli.solve_cmd startrack.identify.image_epoch
    startrack.cli.solve_cmd startrack.io.wcs
    startrack.cli.solve_rig_cmd startrack.multihead.images
    startrack.cli.solve_rig_cmd startrack.multihead.report
    startrack.cli.solve_rig_cmd startrack.multihead.solution
    startrack.cli.solve_rig_cmd startrack.multihead.solve
    startrack.cli.solve_rig_cmd startrack.multihead.stars
    startrack.cli.solve_stars_cmd startrack.identify.image_epoch
    startrack.cli.solve_stars_cmd startrack.identify.request
    startrack.cli.solve_stars_cmd startrack.io.limits
    startrack.cli.track_cmd startrack.io.image
    startrack.cli.track_cmd startrack.io.limits
    startrack.cli.track_cmd startrack.io.targets
    startrack.cli.track_cmd startrack.io.track_csv
    startrack.cli.track_cmd startrack.rate.streak_solve
    startrack.cli.web_cmd startrack.web.app
    startrack.cli.web_cmd startrack.web.config
    startrack.detect.channels startrack.io.channels
    startrack.detect.dark startrack.io.channels
    startrack.detect.detector startrack.io.channels
    startrack.detect.predictive startrack.io.channels
    startrack.identify.database startrack.catalog.thinning
    startrack.identify.image_epoch startrack.calibrate.ground
    startrack.identify.match_groups startrack.attitude.qmethod
    startrack.identify.pair_search startrack.attitude.qmethod
    startrack.identify.pyramid startrack.attitude.qmethod
    startrack.multihead.exclusion startrack.simulate.orbits
    startrack.multihead.joint startrack.attitude.covariance
    startrack.multihead.joint startrack.attitude.qmethod
    startrack.multihead.pattern startrack.attitude.covariance
    startrack.multihead.pattern startrack.attitude.qmethod
    startrack.multihead.pattern startrack.identify.field_stars
    startrack.multihead.pattern startrack.identify.pair_database
    startrack.multihead.pattern startrack.identify.pyramid
    startrack.multihead.pattern startrack.identify.star_order
    startrack.multihead.pattern startrack.track.windows
    startrack.multihead.predict startrack.identify.field_stars
    startrack.multihead.predict startrack.track.windows
    startrack.multihead.solve startrack.identify.registry
    startrack.multihead.solve startrack.track.windows
    startrack.multihead.tracking startrack.track.inputs
    startrack.multihead.tracking startrack.track.tracker
    startrack.multihead.tracking startrack.track.windows
    startrack.rate.catalog_free startrack.attitude.olae
    startrack.rate.streak_predict startrack.identify.field_stars
    startrack.rate.streak_solve startrack.attitude.covariance
    startrack.rate.streak_solve startrack.identify.quad_matcher
    startrack.rig startrack.io.atomic
    startrack.simulate.rig startrack.multihead.exclusion
    startrack.solve startrack.identify.candidate
    startrack.solve startrack.identify.field_stars
    startrack.solve startrack.identify.final_fit
    startrack.solve startrack.identify.image_epoch
    startrack.solve startrack.identify.refine
    startrack.solve startrack.identify.registry
    startrack.solve startrack.identify.request
    startrack.track.relative startrack.attitude.qmethod
    startrack.track.relative startrack.identify.pyramid
    startrack.track.tracker startrack.multihead.tracking
    startrack.track.tracker startrack.rate.smear_mode
    startrack.track.tracker startrack.rate.streak_predict
    startrack.track.tracker startrack.rate.streak_solve
    startrack.track.tracker startrack.rate.streak_track
    startrack.track.tracker startrack.simulate.snr
    startrack.track.windows startrack.identify.field_stars
    startrack.track.windows startrack.identify.verify
    startrack.warm_up startrack.identify.registry
    startrack.web.annotate startrack.analysis.plots
    startrack.web.annotate startrack.io.atomic
    startrack.web.batches startrack.io.image
    startrack.web.jobs startrack.io.atomic
    startrack.web.options startrack.calibrate.sites
    startrack.web.options startrack.identify.registry
    startrack.web.outputs startrack.detect.details
    startrack.web.outputs startrack.io.atomic
    startrack.web.outputs startrack.io.solution_json
    startrack.web.outputs startrack.io.wcs
    startrack.web.pipeline startrack.calibrate.ground
    startrack.web.pipeline startrack.calibrate.ground_solve
    startrack.web.pipeline startrack.calibrate.selfcal
    startrack.web.pipeline startrack.calibrate.sites
    startrack.web.pipeline startrack.calibrate.stars
    startrack.web.records startrack.analysis.records
    startrack.web.records startrack.calibrate.sites
    startrack.web.rejects startrack.detect.filters
    startrack.web.simulation startrack.io.truth_files
    startrack.web.uploads startrack.io.image
    startrack.web.views startrack.calibrate.sites
    startrack.web.worker startrack.identify.registry
""".strip().splitlines()} | {line.strip(): NOT_YET_PUBLIC for line in """
    startrack.analysis.campaign.levels.prefilter startrack.detect.prefilters
    startrack.analysis.campaign.levels.rso startrack.rate.streak_rate
    startrack.analysis.postprocess.repeatability startrack.calibrate.repeatability
    startrack.cli.rate_cmd startrack.rate.streak_rate
    startrack.multihead.availability startrack.analysis.availability
    startrack.multihead.joint startrack.attitude._inputs
    startrack.multihead.solve startrack.identify.field_stars
    startrack.multihead.tracking startrack.identify.field_stars
    startrack.rate.streak_solve startrack.identify.field_stars
    startrack.rate.streak_track startrack.identify.field_stars
    startrack.solve startrack.rate.streak_image
    startrack.track.tracker startrack.identify.field_stars
    startrack.track.tracker startrack.rate.streak_rate
    startrack.web.outputs startrack.analysis.postprocess.core
    startrack.rate.streak_image startrack.identify.registry
    startrack.rate.streak_solve startrack.identify.registry
    startrack.solve startrack.identify.options_base
    startrack.web.pipeline startrack.identify.registry
    startrack.web.pipeline startrack.analysis.postprocess.corrections
    startrack.web.pipeline startrack.analysis.postprocess.ground
    startrack.web.pipeline startrack.analysis.postprocess.records_io
""".strip().splitlines()}
"""``"importer target"`` -> why ``importer`` still imports ``target`` (a module of another
subpackage) rather than the subpackage. Measured on 2026-12-02: 215 pairs (204 from modules of
subpackages, 11 from top-level modules such as ``startrack.solve``), 198 of them importing only
names that are public now."""


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
