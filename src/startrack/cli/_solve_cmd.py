"""startrack solve IMAGE: lost-in-space attitude of an image (FITS, PNG, JPEG, TIFF, 8 or 16 bit,
grey or colour; HEIC; camera RAW). Stars are detected and identified against Hipparcos with no prior attitude; give
the field of view if you know it (faster, more robust; 0.5 to 150 deg), else 3 to 100 deg are
searched, after the field the image's header states when it lies beyond them (an ultra-wide lens's
EXIF focal length, a FITS WCS's scale, a telescope's FOCALLEN and XPIXSZ), or before 90 to 150 deg
when the header states none and nothing matched. The catalog epoch is --epoch, else the time of
--time, else the time the image's header states (FITS CATEPOCH, DATE-OBS or MJD-OBS, EXIF
DateTimeOriginal), else J2000.0; the solution says which (epoch_jyear, epoch_source). A frame whose
stars smear into streaks is solved from them without being asked: the output then says mode
"streak", the mid-exposure time the attitude refers to (t_mid_s, from the header's EXPTIME /
EXPOSURE / ExposureTime) and the fitted rate (rate_deg_s, rate_status, time_order_known)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from ..errors import InvalidInputError, require
from ..identify import resolve_epoch, stated_fov_deg, stated_search_range
from ..io import Image, read_image
from ..results import AttitudeSolution, Detections, Status
from ..solve import solve_image
from ._batch import add_batch_options, batch_epilog, is_batch
from ._batch_warmup import warm_up
from ._common import (
    SOLUTION_FORMATS,
    add_epoch_option,
    add_fov_options,
    add_max_pixels_option,
    add_method_option,
    add_timeout_option,
    announce_mosaic,
    apply_max_pixels_option,
    fov_kwargs,
    method_kwargs,
    non_empty,
    report,
    utc_offset_hours,
)
from ._parser import CommandParser
from ._progress import ensure_database_for
from ._solve_stars_cmd import add_aspect_option, add_parity_option, aspect_option, solver_epoch, time_option


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack solve", description=__doc__,
                           epilog=SOLUTION_FORMATS + "\n" + batch_epilog(),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("image", nargs="+", metavar="IMAGE",
                        help="FITS, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP or camera RAW file; several files or "
                             "folders for a batch")
    add_fov_options(parser)
    add_method_option(parser)
    add_timeout_option(parser)
    parser.add_argument("--channel", choices=("r", "g", "b"),
                        help="colour channel to use (default: the sum R + G + B)")
    add_epoch_option(parser)
    add_aspect_option(parser)
    add_parity_option(parser, "either")
    parser.add_argument("--guided", action="store_true",
                        help="once solved, also measure the catalog stars the solution predicts where nothing was "
                             "detected, keep those that stand above the image's own sky (0.1 wrong ones expected "
                             "per image) and refit the attitude on them too")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--wcs", metavar="OUT", type=non_empty,
                        help="when solved, write the image's FITS WCS (TAN-SIP, FITS 1-based pixels) to OUT "
                             "(one image only)")
    parser.add_argument("--new-fits", metavar="OUT.fits", type=non_empty,
                        help="when solved, write the image as startrack solved it, with its FITS WCS, to OUT.fits "
                             "(astrometry.net's .new; a FITS file's own cards kept, its old WCS replaced; one image "
                             "only)")
    parser.add_argument("--plot", metavar="OUT.png", type=non_empty,
                        help="write a PNG of the image with its detections (grey circles) and, when solved, the "
                             "identified stars (green, HIP numbers) to OUT.png, solved or not (one image only; "
                             "needs matplotlib, the plot extra)")
    add_max_pixels_option(parser)
    add_batch_options(parser)
    ground = parser.add_argument_group(
        "a photo from the ground (adds altitude / azimuth and corrects for aberration and refraction)")
    ground.add_argument("--site", help="a saved or built-in site name (see startrack.calibrate._sites)")
    ground.add_argument("--latitude-deg", type=float, help="site latitude, north positive")
    ground.add_argument("--longitude-deg", type=float, help="site longitude, east positive")
    ground.add_argument("--height-m", type=float, default=0.0, help="site height (default 0 m)")
    ground.add_argument("--time", metavar="UTC",
                        help="UTC time of the photo, ISO 8601 (default: from the EXIF / FITS header); also the "
                             "catalog epoch unless --epoch is given, with or without a site")
    ground.add_argument("--utc-offset-hours", type=utc_offset_hours, help="offset of a local EXIF time from UTC")
    return parser


def _site(args):
    """The site the options name, or None for a photo not taken from the ground."""
    from ..calibrate import Site, get_site

    if args.site:
        return get_site(args.site)
    if args.latitude_deg is None and args.longitude_deg is None:
        return None
    if args.latitude_deg is None or args.longitude_deg is None:
        raise InvalidInputError("give both --latitude-deg and --longitude-deg (or --site NAME)")
    return Site("command-line", args.latitude_deg, args.longitude_deg, args.height_m)


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    apply_max_pixels_option(args)
    solver_options = {**fov_kwargs(args), "epoch": solver_epoch(args), **method_kwargs(args),
                      "pixel_aspect": aspect_option(args), "parity": args.parity, "guided": args.guided}
    fov_options = {key: solver_options[key] for key in ("fov_deg", "fov_range_deg", "camera")}
    if is_batch(args.image, args.csv):
        return _batch(args, solver_options, fov_options)
    args.image = args.image[0]
    image = read_image(args.image, channel=args.channel)
    announce_mosaic(image)
    ensure_database_for(**fov_options, height_ratio=image.data.shape[0] / image.data.shape[1])
    _announce_stated_field(image, fov_options)
    site = _site(args)
    # the compiled kernels loaded (or compiled, with a message) outside the solve time, and the catalog stars
    # of the image's epoch prepared
    warm_up(**fov_options, epoch=None if site is not None else _image_epoch(image, solver_options["epoch"]),
            image=image.data)
    try:
        if site is None:
            solution, ground = solve_image(image, **solver_options), None
        else:
            ground = _solve_ground(image, site, args, solver_options)
            solution = ground.solution
        detections = require(solution.detections, "the image solve's detections")
    except InvalidInputError as exc:  # a problem with this image's content (size, no finite pixel...)
        raise InvalidInputError(f"{args.image}: {exc}") from exc
    if args.wcs and solution.solved:
        from ..io import write_wcs  # astropy.wcs: loaded only when asked for

        write_wcs(args.wcs, solution.rot_cam_from_icrs, require(solution.camera, "the solution's camera"))
    if args.new_fits and solution.solved:
        from ..io import write_solved_fits

        write_solved_fits(args.new_fits, image, solution.rot_cam_from_icrs, require(solution.camera, "its camera"))
    if args.plot:
        _write_plot(args.plot, image, solution, detections)
    return report(explain_blank(solution, detections, image), detections, args.json, ground=ground)


def _batch(args: argparse.Namespace, solver_options: dict, fov_options: dict) -> int:
    """Several images, a folder or --csv: :func:`startrack.cli._batch.run_batch` (lost-in-space only)."""
    from ._batch import run_batch
    from ._batch_solve import solve_spec

    single = {"wcs": "--wcs writes the WCS", "new_fits": "--new-fits writes the image",
              "plot": "--plot draws the picture"}
    option = next((words for key, words in single.items() if getattr(args, key)), None)
    if option is not None:
        raise InvalidInputError(f"{option} of one image; leave it out for a batch")
    if args.site or args.latitude_deg is not None or args.longitude_deg is not None:
        raise InvalidInputError("--site, --latitude-deg and --longitude-deg take one image; leave them out "
                                "for a batch")
    ensure_database_for(**fov_options)
    warm_up(**fov_options, every_detection=True)  # the images' types are not known yet
    return run_batch(solve_spec(solver_options, args.channel), args.image, as_json=args.json,
                     csv_out=args.csv, jobs=args.jobs)


def _write_plot(path: str, image: Image, solution: AttitudeSolution, detections: Detections) -> None:
    """``--plot``: :func:`startrack.analysis.plot_solution` of the image, written by the rules of
    :mod:`startrack.io._atomic` (never over the image read; the whole file or nothing)."""
    from ..analysis import plot_solution  # matplotlib: loaded only when asked for
    from ..io import atomic_path

    with atomic_path(path, inputs=[] if image.path is None else [image.path]) as tmp:
        plot_solution(image.data, detections, solution, tmp)


def _announce_stated_field(image: Image, fov_options: dict) -> None:
    """With no field of view given and one stated by the image's header beyond the default search
    (:func:`startrack.identify.stated_search_range`): say on standard error that it is searched
    first, and build its pattern database now (with a progress bar the first time)."""
    if any(value is not None for value in fov_options.values()):
        return
    height, width = image.data.shape[:2]
    stated = stated_search_range(image.header, width, height)
    if stated is None:
        return
    sys.stderr.write(f"the image's header states a field of view of {stated_fov_deg(image.header, width, height):.1f} "
                     f"deg: searching {stated[0]:.1f}-{stated[1]:.1f} deg first\n")
    ensure_database_for(fov_range_deg=stated)


def _image_epoch(image: Image, epoch) -> float | None:
    """The catalog epoch the solve of ``image`` will take (Julian year), or None when its header
    states a time that cannot be read (the solve then says so, naming the file)."""
    try:
        return resolve_epoch(epoch, image.header).jyear
    except InvalidInputError:
        return None


def _solve_ground(image, site, args, solver_options):
    from ..calibrate import solve_ground_photo

    options = {k: v for k, v in solver_options.items() if k != "epoch"}
    return solve_ground_photo(image, site, time=time_option(args), utc_offset_hours=args.utc_offset_hours, **options)


def explain_blank(solution: AttitudeSolution, detections: Detections, image: Image) -> AttitudeSolution:
    """Name the problem when nothing was detected because every pixel has the same value."""
    if solution.status is not Status.TOO_FEW_STARS or len(detections) or not _uniform(image.data):
        return solution
    value = np.nanmax(image.data)
    saturated = image.data.dtype.kind == "u" and value == np.iinfo(image.data.dtype).max
    what = "saturated" if saturated else "blank"
    return replace(solution, reason=f"no stars: the image is {what}, every pixel is {value:g}")


def _uniform(data: np.ndarray) -> bool:
    finite = data[np.isfinite(data)] if data.dtype.kind == "f" else data
    return finite.size > 0 and np.min(finite) == np.max(finite)
