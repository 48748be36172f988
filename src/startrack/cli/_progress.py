"""A minimal text progress bar on standard error (no dependency), and loading the pattern
database with it so the first run (which builds the database, tens of seconds) shows progress."""

from __future__ import annotations

import sys

from ..camera import Camera


class ProgressBar:
    """Call with (done, total); on a terminal draws ``label [#####     ] done/total`` on one line
    of stderr, elsewhere (a log, a pipe) writes a plain ``label: done/total`` line at each tenth."""

    def __init__(self, label: str, width: int = 30):
        self.label, self.width = label, width
        self.tty = sys.stderr.isatty()
        self._tenth = -1
        self._open = False

    def close(self) -> None:
        """End a bar left part-drawn (a run stopped by an error), so the next line starts clean."""
        if self._open:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self._open = False

    def __call__(self, done: int, total: int) -> None:
        if not self.tty:
            tenth = 10 * done // max(total, 1)
            if tenth > self._tenth:
                self._tenth = tenth
                sys.stderr.write(f"{self.label.strip()}: {done}/{total}\n")
            return
        filled = int(self.width * done / max(total, 1))
        sys.stderr.write(f"\r{self.label} [{'#' * filled}{' ' * (self.width - filled)}] {done}/{total}")
        self._open = done < total
        if not self._open:
            sys.stderr.write("\n")
        sys.stderr.flush()


def ensure_database(fov_range_deg: tuple[float, float] | None = None, height_ratio: float = 1.0) -> None:
    """Load (building on first use, with a progress bar) the pattern database for a FOV range (deg);
    nothing for a range too narrow for the catalog (:func:`startrack.solve.too_sparse_to_solve`
    of its widest field, ``height_ratio`` times as high as wide: the solve fails at once, saying
    why)."""
    from ..identify import DEFAULT_FOV_RANGE_DEG, database_settings_for, is_cached, load_database
    from ..solve import too_sparse_to_solve

    low, high = fov_range_deg if fov_range_deg else DEFAULT_FOV_RANGE_DEG
    if too_sparse_to_solve(high, height_ratio):
        return
    settings = database_settings_for((low, high))
    if not is_cached(settings):
        sys.stderr.write("building the star-pattern database (first run only; it is cached)\n")
        load_database(settings, progress=ProgressBar("  FOV levels"))
    else:
        load_database(settings)


def ensure_database_for(fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                        camera: Camera | None = None, height_ratio: float = 1.0) -> None:
    """:func:`ensure_database` for the FOV range a solve with these (checked) options searches, on
    an image ``height_ratio`` times as high as wide on the sky (the camera's, when one is given)."""
    from ..solve import FOV_DEG_TOLERANCE

    if camera is not None:
        fov_range_deg = (camera.fov_deg, camera.fov_deg)
        height_ratio = camera.fov_height_deg / camera.fov_deg
    elif fov_deg is not None:
        fov_range_deg = (fov_deg * (1 - FOV_DEG_TOLERANCE), fov_deg * (1 + FOV_DEG_TOLERANCE))
    ensure_database(fov_range_deg, height_ratio)
