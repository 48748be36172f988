"""startrack detect IMAGE: find and centroid the stars of an image, brightest first.

Prints one row per star: x, y in our pixel convention (0-based pixel centres, x = column;
add 1 for FITS / astrometry.net), flux (background subtracted, image units), sigma_px (1-sigma
centroid error per axis), instrument magnitude, peak SNR, area and shape. --json prints the
same records with every field of startrack.detect.DetectionDetails, plus the frame's
background, noise, size, threshold and the settings used.
"""

from __future__ import annotations

import argparse

from ..detect import CENTROIDERS, THRESHOLDS, DetectionDetails, StarDetector
from ..errors import InvalidInputError, require
from ..io import read_image
from ._batch import add_batch_options, batch_epilog, is_batch
from ._batch_warmup import warm_up_detection
from ._common import (
    add_max_pixels_option,
    announce_mosaic,
    apply_max_pixels_option,
    exit_status_epilog,
    positive_count,
    print_json,
)
from ._parser import CommandParser

EXIT_STATUS = exit_status_epilog("0 done (also when no star is found); 2 misuse (bad option, unreadable file or "
                                 "invalid image), with one line 'startrack detect: error: ...' on standard error;")


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack detect", description=__doc__,
                           epilog=EXIT_STATUS + "\n" + batch_epilog(),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("image", nargs="+", metavar="IMAGE",
                        help="FITS, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP or camera RAW file; several files or "
                             "folders for a batch")
    parser.add_argument("--method", choices=CENTROIDERS, default=StarDetector.centroid,
                        help="centroider (default: %(default)s)")
    parser.add_argument("--threshold", choices=THRESHOLDS, default=StarDetector.threshold,
                        help="threshold method (default: %(default)s)")
    parser.add_argument("--sigma", type=float, default=StarDetector.sigma,
                        help="detection threshold in noise units (default: %(default)s)")
    parser.add_argument("--dark", metavar="FILE", help="dark or median frame to subtract")
    parser.add_argument("--max-stars", type=positive_count, metavar="N",
                        help="print only the N brightest")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_max_pixels_option(parser)
    add_batch_options(parser)
    return parser


def table(details: DetectionDetails) -> str:
    """The human-readable table of :func:`main`."""
    det = details.detections
    head = (f"{len(det)} stars in {det.width} x {det.height} px; background {det.background:.2f},"
            f" noise {det.noise:.3f}; threshold {details.k_sigma:.2f} sigma; "
            f"centroid {details.centroid}")
    lines = [head, f"{'x':>9} {'y':>9} {'flux':>11} {'sigma_px':>8} {'mag':>7} {'snr':>7} "
                   f"{'area':>5} {'elong':>5}"]
    for i in range(len(det)):
        lines.append(f"{det.x[i]:9.3f} {det.y[i]:9.3f} {det.flux[i]:11.1f} {det.sigma_px[i]:8.4f} "
                     f"{details.mag[i]:7.3f} {details.peak_snr[i]:7.1f} {det.area_px[i]:5d} "
                     f"{det.elongation[i]:5.2f}")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    apply_max_pixels_option(args)
    batch = is_batch(args.image, args.csv)
    image = None if batch else read_image(args.image[0])
    warm_up_detection(None if image is None else image.data, every_detection=batch)  # compiling announced
    dark = None if args.dark is None else read_image(args.dark).data
    detector = StarDetector(centroid=args.method, threshold=args.threshold, sigma=args.sigma,
                            dark_frame=dark, max_stars=args.max_stars)
    if batch:
        from ._batch import run_batch
        from ._batch_detect import detect_spec

        return run_batch(detect_spec(detector), args.image, as_json=args.json, csv_out=args.csv, jobs=args.jobs)
    image = require(image, "the image")
    announce_mosaic(image)
    if dark is not None and dark.shape[:2] != image.data.shape:
        height, width = image.data.shape
        raise InvalidInputError(f"--dark {args.dark} is {dark.shape[1]} x {dark.shape[0]} px and {args.image[0]} "
                                f"{width} x {height} px; a dark frame must have the image's size")
    detector = detector.for_image(image)  # a JPEG's noise floor, in the settings the JSON records
    try:
        details = detector.detect_details(image.data)
    except InvalidInputError as exc:  # a problem with this image's content (no finite pixel, too small)
        raise InvalidInputError(f"{args.image[0]}: {exc}") from exc
    if args.json:
        print_json(json_record(args.image[0], details, detector))
    else:
        print(table(details))
    return 0


def json_record(image, details: DetectionDetails, detector: StarDetector) -> dict:
    """The ``--json`` object of one image (also each line of a batch's ``--json``)."""
    det = details.detections
    return {"image": str(image), "width": det.width, "height": det.height,
            "background": float(det.background), "noise": float(det.noise),
            "k_sigma": details.k_sigma, "centroid": details.centroid,
            "settings": detector.settings(), "stars": details.as_records()}
