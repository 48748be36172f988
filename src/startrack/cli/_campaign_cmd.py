"""``startrack campaign``: Monte Carlo campaigns from a TOML spec (``docs/campaigns.md``).

    startrack campaign run SPEC [--out DIR] [--workers N | --scheduler ADDR | --sync]
                           [--chunk-size N] [--resume] [--no-report]
    startrack campaign report DIR
    startrack campaign rerun DIR --cell C --trial K [--save-image DIR] [--json]
    startrack campaign list [--params LEVEL]

SPEC is a TOML file or the name of a shipped spec (``campaign list``). Exit status 0 when the
campaign ran (whatever its trials did), 2 for a bad spec or options (one line, before any work),
3 for an unexpected error (a fault of startrack's; :data:`startrack.cli._common.FAULT_EXIT_STATUS`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError
from ._common import exit_status_epilog
from ._parser import CommandParser

DEFAULT_OUT = Path("startrack-campaigns")
EXIT_STATUS = exit_status_epilog(
    "0 the campaign ran (whatever its trials did); 2 a bad spec, folder or option, with one line "
    "'startrack campaign: error: ...' on standard error, before any work;")
"""The exit statuses, in the help of the command and of each of its actions."""
EPILOG = """\
SPEC is a TOML file (docs/campaigns.md) or the name of a shipped spec ('startrack campaign list').
'run' writes OUT/manifest.json, OUT/trials/*.parquet (one row per trial), OUT/cells.csv and
OUT/report.html, and prints a table per cell (and the seed's numbers beside ours where the spec
has them). 'rerun --json' prints {"row": {...}, "same_as_stored": true|false|null, "files": [...]}.

""" + EXIT_STATUS


def _needs_extra() -> None:
    for module in ("pyarrow", "distributed"):
        try:
            __import__(module)
        except ImportError:
            raise InvalidInputError(f"campaigns need the campaign extra ({module} is missing): "
                                    "pip install 'startrack[campaign]'") from None


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack campaign", description=__doc__.split("\n\n")[0],
                           epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="action", required=True, metavar="{run,report,rerun,list}")

    def action(name: str, text: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=text, epilog=EXIT_STATUS, formatter_class=argparse.RawDescriptionHelpFormatter)

    run = action("run", "run a campaign spec")
    run.add_argument("spec", help="a TOML spec file, or the name of a shipped spec")
    run.add_argument("--out", type=Path, help=f"output folder (default {DEFAULT_OUT}/NAME)")
    where = run.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="worker processes of a local Dask cluster (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDR", help="an existing Dask scheduler, e.g. tcp://127.0.0.1:8786")
    where.add_argument("--sync", action="store_true", help="run every trial in this process (debugging)")
    run.add_argument("--chunk-size", type=int, metavar="N", help="trials per task (default: the level's)")
    run.add_argument("--resume", action="store_true", help="finish an interrupted campaign in --out")
    run.add_argument("--no-report", action="store_true", help="skip cells.csv and the report")
    report = action("report", "(re)write cells.csv and report.html of a campaign folder")
    report.add_argument("out", type=Path)
    rerun = action("rerun", "reproduce one trial exactly and print its row")
    rerun.add_argument("out", type=Path)
    rerun.add_argument("--cell", type=int, required=True)
    rerun.add_argument("--trial", type=int, required=True)
    rerun.add_argument("--save-image", type=Path, metavar="DIR", help="write the trial's frame (or star list) here")
    rerun.add_argument("--json", action="store_true", help="print the row as JSON")
    listing = action("list", "list the shipped specs, or a level's parameters")
    listing.add_argument("--params", metavar="LEVEL", help="print the parameters of a level (stars, image, ...)")
    return parser


def _run(args: argparse.Namespace) -> int:
    from ..analysis.campaign import find_spec, load_spec, run_campaign
    from ._progress import ProgressBar

    spec = load_spec(find_spec(args.spec))
    out = args.out if args.out is not None else DEFAULT_OUT / spec.name
    n_cells = len(spec.cells())
    print(f"campaign {spec.name}: level {spec.level}, {n_cells} cells x {spec.trials} trials -> {out}",
          file=sys.stderr)
    run_campaign(spec, out, workers=args.workers, scheduler=args.scheduler, sync=args.sync,
                 chunk_size=args.chunk_size, resume=args.resume, progress=ProgressBar("  trials"),
                 report=not args.no_report)
    _print_summary(out, report=not args.no_report)
    return 0


def _print_summary(out: Path, *, report: bool) -> None:
    from ..analysis.campaign import summary_text

    print(summary_text(out))
    if report:
        print(f"\nreport: {out / 'report.html'}")


def _report(args: argparse.Namespace) -> int:
    from ..analysis.campaign import write_report

    path = write_report(args.out)
    _print_summary(args.out, report=False)
    print(f"\nreport: {path}")
    return 0


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _rerun(args: argparse.Namespace) -> int:
    from ..analysis.campaign import rerun_trial

    result = rerun_trial(args.out, args.cell, args.trial, save_dir=args.save_image)
    if args.json:
        print(json.dumps({"row": {k: _plain(v) for k, v in result.row.items()}, "same_as_stored": result.same,
                          "files": [str(p) for p in result.files]}))
        return 0
    width = max(len(k) for k in result.row)
    for key, value in result.row.items():
        text = value.splitlines()[-1] if key == "error" and value else value
        print(f"{key:<{width}}  {text}")
    same = {None: "not stored (its chunk never finished)", True: "yes (times aside)", False: "NO"}[result.same]
    print(f"\nsame as the stored row: {same}")
    for path in result.files:
        print(f"wrote {path}")
    return 0


def _list(args: argparse.Namespace) -> int:
    if args.params:
        from ..analysis.campaign import param_table
        from ..analysis.campaign.levels import get_level

        level = get_level(args.params)
        print(f"level {level.name}: {level.doc}\n")
        for name, valid, default, doc in param_table(level.params):
            print(f"  {name:<22} {default:<14} {doc} ({valid})")
        return 0
    from ..analysis.campaign import list_specs

    specs = list_specs()
    width = max((len(s.name) for s in specs), default=4)
    for spec in specs:
        print(f"{spec.name:<{width}}  {spec.level:<9} {spec.description}")
    print(f"\n{len(specs)} shipped specs; run one with 'startrack campaign run NAME'")
    return 0


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    _needs_extra()
    return {"run": _run, "report": _report, "rerun": _rerun, "list": _list}[args.action](args)
