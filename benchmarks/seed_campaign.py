"""Run a shipped seed-table spec through the campaign engine and print ours beside the seed's.

The seed-table benchmarks (``detect_huffman2006.py``, ``simulate_benchmark.py``,
``huffman2006_table82.py``, ``jacobs1995_matching.py``) are thin: each runs the specs of
``startrack/analysis/campaign/specs/`` (the one implementation of the experiment, in the
campaign levels) with ``run_campaign`` and prints the spec's reference tables
(``startrack.analysis.campaign._reference``). What they may change is what a spec leaves open:
the trials per cell, the campaign seed and ``[base]`` values, by editing the spec's text, so that
the run's manifest holds the spec as run.
"""

from __future__ import annotations

import argparse
import atexit
import re
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import pyarrow as pa

from startrack.analysis.campaign._reference import reference_text
from startrack.analysis.campaign._run import run_campaign
from startrack.analysis.campaign._shipped import find_spec
from startrack.analysis.campaign._spec import CampaignSpec, parse_spec


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def spec_text(name: str, *, trials: int | None = None, seed: int | None = None,
              base: dict[str, Any] | None = None, sweep: dict[str, list] | None = None) -> str:
    """The shipped spec ``name``'s TOML with ``[campaign]`` trials / seed, ``[base]`` values and
    ``[sweep]`` lists replaced (a key the spec does not set is added to its table)."""
    text = find_spec(name).read_text(encoding="utf-8")
    for key, value in (("trials", trials), ("seed", seed)):
        if value is not None:
            text = re.sub(rf"(?m)^{key}\s*=\s*\d+\s*$", f"{key} = {int(value)}", text, count=1)
    for table, values in (("base", base), ("sweep", sweep)):
        for key, value in (values or {}).items():
            text = _set_in_table(text, table, key, _toml_value(value))
    return text


def _set_in_table(text: str, table: str, key: str, value: str) -> str:
    """``key = value`` in the ``[table]`` of ``text`` (a missing ``[base]`` is added before
    ``[sweep]``, a missing ``[sweep]`` before the first ``[[reference]]`` or at the end)."""
    line, header = f"{key} = {value}", f"\n[{table}]\n"
    if header not in text:
        anchor = "\n[sweep]\n" if table == "base" else "\n[[reference]]\n"
        if anchor in text:
            return text.replace(anchor, f"{header}{line}\n{anchor}", 1)
        return f"{text.rstrip()}\n{header}{line}\n"
    head, rest = text.split(header, 1)
    end = re.search(r"(?m)^\[", rest)
    body, tail = (rest[:end.start()], rest[end.start():]) if end else (rest, "")
    body, n = re.subn(rf"(?m)^{re.escape(key)}\s*=.*$", line, body, count=1)
    return f"{head}{header}{body if n else line + chr(10) + body}{tail}"


def run_spec(text: str, out: Path | None, workers: int | None, sync: bool) -> tuple[CampaignSpec, Path, pa.Table]:
    """Run a spec (its TOML text) into ``out`` (a temporary folder when None: removed at exit)
    and return the spec, the folder and the trials."""
    spec = parse_spec(text)
    if out is None:
        tmp = Path(tempfile.mkdtemp(prefix=f"{spec.name}-"))
        atexit.register(shutil.rmtree, tmp, ignore_errors=True)
        out = tmp / "campaign"
    t0 = time.perf_counter()
    trials = run_campaign(spec, out, workers=None if sync else (workers or 2), sync=sync, report=False)
    print(f"campaign {spec.name}: {len(spec.cells())} cells x {spec.trials} trials in "
          f"{time.perf_counter() - t0:.1f} s ({'synchronous' if sync else f'{workers or 2} workers'}) -> {out}",
          flush=True)
    return spec, out, trials


def print_references(out: Path) -> str:
    """Print (and return) the campaign's reference tables: ours beside the seed's."""
    text = reference_text(out)
    print(text, flush=True)
    return text


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """The options every seed-table benchmark takes: where to run and where to keep the output."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="local Dask workers (default 2)")
    where.add_argument("--sync", action="store_true", help="run every trial in this process")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the campaigns' output, one sub-folder per spec (default: temporary)")


def out_for(args: argparse.Namespace, name: str) -> Path | None:
    """The output folder of spec ``name`` under ``--out`` (None: a temporary one)."""
    return None if args.out is None else args.out / name
