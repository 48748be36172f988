"""The matcher registry imports a matcher's modules only when that matcher is asked for."""

import subprocess
import sys

from startrack.identify._registry import MATCHERS, OPTIONS, options_for

PAIR_MODULES = ("_angle_pivot", "_match_groups", "_nvertex", "_overlay", "_pyramid", "_triangles")


def _imported_after(code: str) -> set[str]:
    probe = (f"import sys\n{code}\n"
             "print(' '.join(m.rsplit('.', 1)[-1] for m in sys.modules if m.startswith('startrack.identify.')))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return set(done.stdout.split())


def test_the_registry_imports_no_matcher_and_a_look_up_only_its_own():
    assert not _imported_after("import startrack.identify._registry") & {*PAIR_MODULES, "_quad_matcher"}
    after = _imported_after("from startrack.identify._registry import OPTIONS\nOPTIONS['pyramid']")
    assert "_pyramid" in after and not after & {"_angle_pivot", "_nvertex", "_triangles", "_match_groups", "_overlay"}


def test_every_matcher_has_its_options_class():
    assert list(OPTIONS) == list(MATCHERS) and len(OPTIONS) == len(MATCHERS)
    for method in MATCHERS:
        assert OPTIONS[method].__module__.startswith("startrack.identify.")
        assert isinstance(options_for(method), OPTIONS[method])
    assert OPTIONS["nvertex-3"] is OPTIONS["nvertex-5"]
