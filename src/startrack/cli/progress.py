"""A minimal text progress bar on standard error (no dependency)."""

from __future__ import annotations

import sys


class ProgressBar:
    """Call with (done, total); draws ``label [#####     ] done/total`` on one line of stderr."""

    def __init__(self, label: str, width: int = 30):
        self.label, self.width = label, width

    def __call__(self, done: int, total: int) -> None:
        filled = int(self.width * done / max(total, 1))
        sys.stderr.write(f"\r{self.label} [{'#' * filled}{' ' * (self.width - filled)}] {done}/{total}")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def ensure_database(fov_range_deg=None) -> None:
    """Load (building on first use, with a progress bar) the pattern database for a FOV range."""
    from ..identify import load_database
    from ..identify.database import is_cached
    from ..solve import DEFAULT_FOV_RANGE_DEG, database_settings_for

    settings = database_settings_for(tuple(fov_range_deg) if fov_range_deg else DEFAULT_FOV_RANGE_DEG)
    if not is_cached(settings):
        sys.stderr.write("building the star-pattern database (first run only; it is cached)\n")
        load_database(settings, progress=ProgressBar("  FOV levels"))
    else:
        load_database(settings)
