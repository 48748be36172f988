"""startrack analyse: the post-processing analyses of Fowler 2013 ch. 8 over result sets of images
(figure as PNG, its numbers as CSV).

  startrack analyse list
  startrack analyse NAME PATH [PATH2] [--out DIR] [--param KEY=VALUE ...] [--fov-deg F | ...]

Each PATH is an image file or a folder of images, detected and solved into one result set; the
analysis NAME runs over the sets and writes NAME.png and NAME_<table>.csv to --out (default
./startrack-analysis/NAME), then prints its summary. See docs/analysis.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..analysis.postprocess import (
    ANALYSES,
    UNREADABLE,
    AnalysisInfo,
    check_params,
    get_info,
    parse_param,
    records_from_images,
    run_analysis,
)
from ..errors import InvalidInputError
from ._common import (
    add_fov_options,
    add_max_pixels_option,
    apply_max_pixels_option,
    check_output_folder,
    exit_status_epilog,
    fov_kwargs,
    non_empty,
    utc_offset_hours,
)
from ._parser import CommandParser
from ._progress import ProgressBar, ensure_database_for

EPILOG = exit_status_epilog(
    "0 the analysis ran (its files are written); 2 misuse (unknown analysis, bad --param, missing path, wrong "
    "number of PATHs, no image that could be read), with one line 'startrack analyse: error: ...' on standard "
    "error;",
    "Images that cannot be read or solved do not stop the run: they count as unsolved (unless none could be read).")


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack analyse", description=__doc__, epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("name", metavar="NAME", help="an analysis ('list' shows them with their parameters)")
    parser.add_argument("paths", metavar="PATH", nargs="*", help="image file or folder of images (one result set each)")
    parser.add_argument("--out", metavar="DIR", type=non_empty,
                        help="output folder (default ./startrack-analysis/NAME)")
    parser.add_argument("--param", metavar="KEY=VALUE", action="append", default=[],
                        help="a parameter of the analysis (repeatable); lists as 3,4,5")
    add_fov_options(parser)
    parser.add_argument("--channel", choices=("r", "g", "b"), help="colour channel (default R + G + B)")
    parser.add_argument("--utc-offset-hours", type=utc_offset_hours,
                        help="offset of the cameras' EXIF clock from UTC, for image times without a zone")
    add_max_pixels_option(parser)
    return parser


def list_text() -> str:
    """The analyses, their titles, set counts and parameters, as text."""
    lines = []
    for info in ANALYSES.values():
        sets = str(info.min_sets) if info.min_sets == info.max_sets else f"{info.min_sets}-{info.max_sets}"
        images = ", reads the pixels" if info.needs_images else ""
        lines.append(f"{info.name:<14}{info.title} ({sets} result set(s){images})")
        for key, (kind, default, text) in info.params.items():
            lines.append(f"{'':<16}{key}={default!r} ({kind.__name__}): {text}")
    return "\n".join(lines)


def parse_params(info: AnalysisInfo, items: list[str]) -> dict:
    """``KEY=VALUE`` items as the analysis's checked parameters."""
    given = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise InvalidInputError(f"--param must be KEY=VALUE, got {item!r}")
        given[key.strip()] = parse_param(info, key.strip(), text)
    return check_params(info, given)


def _set_names(paths: list[str]) -> list[str]:
    names = [Path(p).name or str(p) for p in paths]
    return names if len(set(names)) == len(names) else [str(p) for p in paths]


def main(argv: list[str]) -> int:
    """``startrack analyse``: list, or run one analysis over the PATHs (exit 0; misuse raises and exits 2)."""
    args = _parser().parse_args(argv)
    apply_max_pixels_option(args)
    if args.name == "list":
        print(list_text())
        return 0
    info = get_info(args.name)
    params = parse_params(info, args.param)
    n_range = f"{info.min_sets}" if info.min_sets == info.max_sets else f"{info.min_sets} to {info.max_sets}"
    if not info.min_sets <= len(args.paths) <= info.max_sets:
        raise InvalidInputError(f"{info.name} takes {n_range} PATH(s), got {len(args.paths)}")
    for path in args.paths:
        if not Path(path).exists():
            raise InvalidInputError(f"{path}: no such file or folder")
    out = Path(args.out) if args.out else Path("startrack-analysis") / info.name
    check_output_folder(out)  # before the solves, not after them
    options = {**fov_kwargs(args), "channel": args.channel, "utc_offset_hours": args.utc_offset_hours}
    ensure_database_for(options["fov_deg"], options["fov_range_deg"], options["camera"])
    sets = [_solve(path, name, options) for path, name in zip(args.paths, _set_names(args.paths), strict=True)]
    _check_something_read(sets)
    result = run_analysis(info.name, sets, params)
    written = result.write(out)
    print(_summary_text(result, sets, written))
    return 0


def _solve(path: str, name: str, options: dict):
    progress = ProgressBar(f"solving {name}") if sys.stderr.isatty() else None
    result = records_from_images([path], solve_options=options, progress=progress, name=name)
    for record in result.records:  # say why an image gives nothing (unreadable, too large, not solved)
        solution = record.solution
        if solution.reason.startswith(UNREADABLE):
            print(f"{record.name}: {solution.reason}", file=sys.stderr)
        elif not solution.solved:
            print(f"{record.name}: {solution.status.name.lower()}: {solution.reason}", file=sys.stderr)
    return result


def _check_something_read(sets) -> None:
    """Refuse a run in which no image of any set could be read (it wrote empty figures, exit 0)."""
    records = [record for result_set in sets for record in result_set.records]
    if records and all(record.solution.reason.startswith(UNREADABLE) for record in records):
        first = records[0].solution.reason.removeprefix(UNREADABLE)
        raise InvalidInputError(f"no image could be read ({len(records)} tried; the first: {first})")


def _summary_text(result, sets, written) -> str:
    solved = ", ".join(f"{s.name}: {sum(r.solution.solved for r in s.records)} of {len(s.records)} solved"
                       for s in sets)
    width = max([len("images"), *map(len, result.summary)]) + 2
    lines = [result.title, f"{'images':<{width}}{solved}"]
    lines += [f"{key:<{width}}{_format(value)}" for key, value in result.summary.items()]
    lines.append("wrote " + ", ".join(str(p) for p in written))
    return "\n".join(lines)


def _format(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)
