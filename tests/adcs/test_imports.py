"""The core never imports startrack.adcs (DESIGN.md §2: a consumer of the library)."""

from __future__ import annotations

import subprocess
import sys

CODE = """
import sys
import startrack, startrack.solve, startrack.track, startrack.simulate
print(sorted(m for m in sys.modules if m.startswith('startrack.adcs')))
import startrack.adcs._lgl  # the check sees it when it happens
print(sorted(m for m in sys.modules if m.startswith('startrack.adcs')))
"""


def test_core_packages_do_not_import_adcs():
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, check=True).stdout
    before, after = out.strip().splitlines()
    assert before == "[]"
    assert "startrack.adcs._lgl" in after
