"""A solve that loads what a first real solve would: the 30 brightest catalog stars a camera
pointed at RA 90, Dec 30 deg sees, solved with the field-of-view options of the work to come, so
that the pattern database and the compiled kernels are loaded (or, once after an install,
compiled) before any timed solve. Used by the CLI's warm-up (:mod:`startrack.cli._batch_warmup`)
and by the web server's fork server (:mod:`startrack.web._worker`)."""

from __future__ import annotations

import math

from .camera import Camera


def warm_up_fov_deg(fov_deg: float | None, fov_range_deg: tuple[float, float] | None,
                     camera: Camera | None) -> float:
    """The field of view of the warm-up star list: the one the command will search (deg)."""
    from .identify import DEFAULT_FOV_RANGE_DEG

    if camera is not None:
        return camera.fov_deg
    if fov_deg is not None:
        return fov_deg
    lo, hi = fov_range_deg or DEFAULT_FOV_RANGE_DEG
    return math.sqrt(lo * hi)


def solve_catalog_stars(fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                        camera: Camera | None = None, epoch: float | None = None) -> None:
    """Solve the 30 brightest catalog stars a camera pointed at RA 90, Dec 30 deg sees, with the
    field-of-view options of the command (so the same pattern database is used), at the catalog
    ``epoch`` (Julian year, default J2000.0; the solver's catalog stars of that epoch are then
    ready for the solve to come)."""
    import numpy as np

    from .catalog import load_catalog
    from .frames import radec_to_vector, rotation_from_radec_roll
    from .solve import solve_stars

    catalog = load_catalog()
    view = camera or Camera.from_fov(1024, 1024, warm_up_fov_deg(fov_deg, fov_range_deg, None))
    rot = rotation_from_radec_roll(math.radians(90.0), math.radians(30.0), 0.0)
    vectors = rot.apply(radec_to_vector(catalog.ra_rad, catalog.dec_rad))
    ahead = vectors[:, 2] > math.cos(math.radians(view.fov_diagonal_deg / 2))
    x, y = view.vector_to_pixel(vectors[ahead])
    seen = np.flatnonzero(view.in_image(x, y, margin_px=2.0))
    order = seen[np.argsort(catalog.v_mag[ahead][seen], kind="stable")[:30]]
    options = {"camera": camera} if camera is not None else {"fov_deg": fov_deg, "fov_range_deg": fov_range_deg}
    solve_stars(x[order], y[order], width=view.width, height=view.height, epoch=epoch, **options)
