"""Solving a photo taken from the ground: where the camera pointed in RA / Dec and in altitude /
azimuth, with the atmosphere taken into account (Fowler 2013 Ch. 2 and 5; issue 7 item 4).

1. The time comes from the image header (EXIF ``DateTimeOriginal`` or FITS ``DATE-OBS``,
   :func:`.ground.time_from_header`) unless given.
2. The image is solved lost-in-space (:func:`startrack.solve_image`) with the catalog at that
   epoch.
3. The matched stars' catalog directions are turned into what the camera saw: geocentric apparent
   place (:func:`.apparent.apparent_vectors`: space motion, parallax, light deflection, annual
   aberration) and then refraction at the site (:func:`.ground.refract_icrs`: raised towards the
   zenith, Bennett's formula with the site's temperature and pressure).
4. The attitude is refitted to those directions (q-method): it now maps the apparent, unrefracted
   sky (ICRS axes) into the camera frame, so RA / Dec of the boresight is where it really points,
   and altitude / azimuth follow from the site and time (the altitude reported is the apparent one,
   refraction included, as a levelled instrument would read it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ..attitude import q_method_quaternions
from ..catalog import load_catalog
from ..errors import require
from ..frames import angle_between, radec_roll_from_rotation
from ..io import Image, read_image
from ..results import AttitudeSolution
from ..solve import solve_image
from ..units import ARCSEC
from ._apparent import apparent_vectors
from ._ground import pointing_altaz, refract_icrs, time_from_header
from ._sites import Site


@dataclass(frozen=True)
class GroundSolution:
    """A ground photo's solution: the attitude against the apparent, refracted sky, the time and
    site used, and the boresight's apparent altitude and azimuth (degrees, azimuth east of north)."""

    solution: AttitudeSolution
    time: Time
    site: Site
    altitude_deg: float = math.nan
    azimuth_deg: float = math.nan


def solve_ground_photo(image, site: Site, *, time: Time | None = None, utc_offset_hours: float | None = None,
                       channel: str | int | None = None, **solve_options) -> GroundSolution:
    """Solve a sky photo from ``site`` and refit it to the apparent, refracted star directions.

    Parameters
    ----------
    image : path, array or startrack.io.Image
        The photo (see :func:`startrack.io.read_image`).
    site : Site
        Where it was taken (:func:`startrack.calibrate._sites.get_site` for saved sites).
    time : astropy.time.Time, optional
        When; default from the header (local EXIF times need ``utc_offset_hours``).
    solve_options
        ``fov_deg``, ``fov_range_deg``, ``camera``, ``method`` ... as in :func:`startrack.solve_image`.
    """
    img = image if isinstance(image, Image) else read_image(image, channel=channel)
    when = time if time is not None else time_from_header(img.header, utc_offset_hours=utc_offset_hours)
    solution = solve_image(img, epoch=when, **solve_options)
    if not solution.solved:
        return GroundSolution(solution, when, site)
    solution = _refit_to_sky(solution, when, site)
    alt, az = pointing_altaz(solution.rot_cam_from_icrs, when, site)
    return GroundSolution(solution, when, site, alt, az)


def _refit_to_sky(solution: AttitudeSolution, when: Time, site: Site) -> AttitudeSolution:
    catalog = load_catalog()
    rows = np.searchsorted(catalog.hip, solution.matches.hip)  # the catalog is sorted by HIP
    reference = refract_icrs(apparent_vectors(catalog.take(rows), when), when, site)
    det = require(solution.detections, "the solution's detections")
    idx = solution.matches.det_index
    observed = require(solution.camera, "the solution's camera").pixel_to_vector(det.x[idx], det.y[idx])
    weights = np.full((1, len(idx)), 1.0 / len(idx))
    rot = Rotation.from_quat(q_method_quaternions(observed[None], reference[None], weights)[0])
    ra, dec, roll = (float(np.degrees(a)) for a in radec_roll_from_rotation(rot))
    residuals = angle_between(rot.apply(reference), observed) / ARCSEC
    matches = replace(solution.matches, cat_vectors=reference)
    return replace(solution, rot_cam_from_icrs=rot, ra_deg=ra, dec_deg=dec, roll_deg=roll, matches=matches,
                   residuals_arcsec=residuals)
