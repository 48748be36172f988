"""The campaign report: ``cells.csv``, ``figures/*.png``, ``data/*.csv`` and ``report.html``.

``report.html`` is one self-contained page (its own inline CSS, no JavaScript, no network): the
spec and its provenance, the cells table, every figure with links to the CSV of its numbers, the
reference tables (ours beside the seed's), the sections registered in :data:`SECTIONS`, and the
worst trials with the command that reruns each. Every file is written atomically (temporary file,
then rename), and ``report.html`` last, so an interrupted report leaves whole files only.
"""

from __future__ import annotations

import html
import importlib
import shlex
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.compute as pc

from ...io import atomic_path
from ._aggregate import FAILED, cell_table, read_campaign, status_table, write_csv
from ._figures import ReportFigure, report_figures
from ._reference import ReferenceTable, fmt, reference_tables

Section = Callable[[dict[str, Any], pa.Table, Path], "str | None"]
SECTIONS: list[Section] = []
"""Extra report sections, called in order after the reference tables as ``fn(manifest, trials, out)``;
each returns an HTML fragment (escaped by its author; it may write its own files under ``out``,
atomically) or None to add nothing. Add one with :func:`register_section`."""

SECTION_MODULES: dict[str, tuple[str, ...]] = {"budget": ("startrack.analysis.campaign._budget",)}
"""Modules imported before the sections run, by campaign mode, so that their
:func:`register_section` calls have happened in a fresh process (``startrack campaign report``)."""

WORST = 10
MAX_FAILED = 25

CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 80em; color: #222; line-height: 1.4; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
th, td { border: 1px solid #ddd; padding: 0.25em 0.5em; text-align: right; vertical-align: top; }
th { background: #f3f3f3; } td.l, th.l { text-align: left; } td.c { text-align: left; white-space: nowrap; }
tr:nth-child(even) td { background: #fafafa; }
code, pre { font-family: ui-monospace, monospace; font-size: 0.85em; }
pre { background: #f6f6f6; padding: 0.8em; overflow-x: auto; border: 1px solid #e3e3e3; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; max-width: 60em; }
.warn { background: #fff4d6; border: 1px solid #e6c200; padding: 0.5em 0.8em; }
.err { color: #a00; }
"""


def register_section(fn: Section) -> Section:
    """Add ``fn`` to :data:`SECTIONS` (once; usable as a decorator) and return it."""
    if fn not in SECTIONS:
        SECTIONS.append(fn)
    return fn


def esc(value: Any) -> str:
    """``value`` as escaped HTML text."""
    return html.escape(str(value), quote=True)


class Code(str):
    """A table value shown as code, on one line (a command)."""


def html_table(header: list[str], rows: list[list[Any]], left: int = 1) -> str:
    """A table; the first ``left`` columns and :class:`Code` values left-aligned, values escaped."""
    def cell(tag: str, j: int, v: Any) -> str:
        if isinstance(v, Code):
            return f"<{tag} class=c><code>{esc(v)}</code></{tag}>"
        return f"<{tag}{' class=l' if j < left else ''}>{esc(v)}</{tag}>"
    head = "".join(cell("th", j, h) for j, h in enumerate(header))
    body = "".join("<tr>" + "".join(cell("td", j, v) for j, v in enumerate(r)) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def rerun_command(out: Path, cell: int, trial: int) -> str:
    """The command that reruns trial ``trial`` of cell ``cell``."""
    return Code(f"startrack campaign rerun {shlex.quote(str(out))} --cell {cell} --trial {trial}")


def _head(manifest: Mapping[str, Any], trials: pa.Table) -> str:
    expected = len(manifest["cells"]) * int(manifest.get("trials_per_cell", 0))
    spec = manifest.get("spec", {}).get("campaign", {})
    text = (f"<h1>Campaign {esc(manifest.get('name', ''))}</h1><p>{esc(spec.get('description', ''))}</p>"
            f"<p>level <b>{esc(manifest.get('level'))}</b>, mode {esc(manifest.get('mode', 'sweep'))}, "
            f"{len(manifest['cells'])} cells x {esc(manifest.get('trials_per_cell'))} trials, "
            f"{trials.num_rows} trials on disk. Correct: {esc(manifest.get('correct', {}).get('definition', ''))}.</p>")
    if manifest.get("finished_utc") is None or trials.num_rows < expected:
        text += (f"<p class=warn>This campaign has not finished: {trials.num_rows} of {expected} trials are on "
                 "disk (still running, or interrupted: finish it with <code>--resume</code>).</p>")
    return text


def _provenance(manifest: Mapping[str, Any]) -> str:
    keys = ("package_version", "git_commit", "catalog_hash", "database_hashes", "seed", "started_utc",
            "finished_utc", "hosts", "workers", "chunk_size")
    rows = [[k, ", ".join(map(str, v)) if isinstance(v, list) else ("-" if v is None else v)]
            for k in keys if k in manifest for v in [manifest[k]]]
    runs = [[r.get("started_utc", ""), r.get("mode", ""), r.get("workers", ""), r.get("chunks", ""),
             fmt(r.get("wall_s", float("nan")))] for r in manifest.get("runs", [])]
    return ("<h2>Spec and provenance</h2>" + html_table(["", "value"], rows, left=2)
            + (html_table(["run started", "mode", "workers", "chunks", "wall (s)"], runs, left=2) if runs else "")
            + f"<pre>{esc(manifest.get('spec_text', ''))}</pre>")


def _rate(row: Mapping[str, Any]) -> str:
    return f"{fmt(row['success_rate'])} [{fmt(row['success_low'])}, {fmt(row['success_high'])}]"


def _pair(row: Mapping[str, Any], a: str, b: str, scale: float = 1.0) -> str:
    return f"{fmt(row[a] * scale)} / {fmt(row[b] * scale)}"


def _cells(cells: pa.Table) -> str:
    header = ["cell", "label", "n", "errors", "success [95 %]", "false (<= 95 % bound)", "cross p50 / p95 (arcsec)",
              "|roll| p50 / p95 (arcsec)", "time p50 / p95 (ms)", "stars"]
    rows = [[r["cell"], r["label"], r["n"], r["n_error"], _rate(r),
             f"{fmt(r['false_rate'])} (<= {fmt(r['false_upper'])})",
             _pair(r, "err_cross_p50_arcsec", "err_cross_p95_arcsec"),
             _pair(r, "err_roll_p50_arcsec", "err_roll_p95_arcsec"),
             _pair(r, "time_p50_s", "time_p95_s", 1e3), fmt(r["n_stars_mean"])] for r in cells.to_pylist()]
    return ("<h2>Cells</h2><p>Every aggregate of every cell: <a href=\"cells.csv\">cells.csv</a> (columns in "
            "docs/campaign_report.md). Errors are over the correct trials.</p>" + html_table(header, rows, 2))


def _status(table: pa.Table) -> str:
    names = table.column_names
    return ("<h2>Outcomes</h2><p>Trials of each status per cell (<a href=\"data/status.csv\">status.csv</a>).</p>"
            + html_table(names, [list(r.values()) for r in table.to_pylist()], 2))


def save_figure(fig: ReportFigure, out: Path) -> tuple[str, list[str]]:
    """Write ``figures/<name>.png`` and its tables ``data/<name>[-<key>].csv`` under ``out`` (atomically);
    return their paths relative to ``out``."""
    png = f"figures/{fig.name}.png"
    with atomic_path(out / png) as tmp:
        fig.figure.savefig(tmp, format="png")
    names = fig.csv_names()
    for key, table in fig.data.items():
        write_csv(table, out / names[key])
    return png, list(names.values())


def _figure(fig: ReportFigure, png: str, csvs: list[str]) -> str:
    links = ", ".join(f'<a href="{esc(c)}">{esc(Path(c).name)}</a>' for c in csvs)
    return (f"<figure><h3>{esc(fig.title)}</h3><img src=\"{esc(png)}\" alt=\"{esc(fig.title)}\">"
            f"<figcaption>{esc(fig.caption)} Numbers: {links}.</figcaption></figure>")


def _references(refs: list[ReferenceTable], csvs: list[str | None]) -> str:
    parts = ["<h2>Ours beside the seed's</h2>"]
    for ref, csv in zip(refs, csvs, strict=True):
        unit = f" ({ref.unit})" if ref.unit else ""
        parts.append(f"<h3>{esc(ref.title)}</h3><p>{esc(ref.source)}; metric <code>{esc(ref.metric)}</code>{esc(unit)}"
                     + (f'; <a href="{esc(csv)}">{esc(Path(csv).name)}</a>' if csv else "") + "</p>")
        if ref.error:
            parts.append(f"<p class=err>Could not be evaluated: {esc(ref.error)}</p>")
            continue
        rows = [[r["label"], fmt(r["ours"]), r["seed"] or "-", fmt(r["difference"]), fmt(r["ratio"]), r["n_trials"],
                 r["note"]] for r in ref.table.to_pylist()]
        parts.append(html_table(["", "ours", "seed", "ours - seed", "ours / seed", "trials", "note"], rows))
    return "".join(parts)


def _last_line(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1].strip() if lines else ""


def _worst(trials: pa.Table, manifest: Mapping[str, Any], out: Path) -> str:
    labels = {c["cell"]: c.get("label", "") for c in manifest["cells"]}
    solved = trials.filter(pc.and_(trials["solved"], pc.is_finite(trials["err_total_arcsec"])))
    worst = solved.sort_by([("err_total_arcsec", "descending")]).slice(0, WORST).to_pylist()
    rows = [[r["cell"], labels.get(r["cell"], ""), r["trial"], "yes" if r["correct"] else "FALSE SOLVE",
             fmt(r["err_total_arcsec"]), fmt(r["err_cross_arcsec"]), fmt(r["err_roll_arcsec"]), r["n_stars"],
             r["n_matched"], f"{fmt(r['ra_deg'])}, {fmt(r['dec_deg'])}", rerun_command(out, r["cell"], r["trial"])]
            for r in worst]
    text = (f"<h2>Worst trials</h2><p>The {len(rows)} solved trials with the largest total attitude error, each "
            "with the command that reruns it exactly.</p>"
            + html_table(["cell", "label", "trial", "correct", "total (arcsec)", "cross (arcsec)", "roll (arcsec)",
                          "stars", "matched", "true RA, Dec (deg)", "rerun"], rows, 2))
    failed = trials.filter(pc.is_in(trials["status"], pa.array(FAILED)))
    if failed.num_rows:
        rows = [[r["cell"], labels.get(r["cell"], ""), r["trial"], r["status"], _last_line(r["error"]),
                 rerun_command(out, r["cell"], r["trial"])] for r in failed.slice(0, MAX_FAILED).to_pylist()]
        text += (f"<h3>Trials that raised (ERROR) or lost their worker (LOST): {failed.num_rows}</h3>"
                 + (f"<p>The first {MAX_FAILED} shown.</p>" if failed.num_rows > MAX_FAILED else "")
                 + "<p>The exception is the last line of the traceback stored in the trial's <code>error</code>.</p>"
                 + html_table(["cell", "label", "trial", "status", "exception", "rerun"], rows, 2))
    return text


def _extra_sections(manifest: dict[str, Any], trials: pa.Table, out: Path) -> list[str]:
    """The registered sections' fragments. A section module that does not import, or a section that
    raises, becomes a paragraph naming it and the exception: the rest of the report is still written."""
    failed = []
    for module in SECTION_MODULES.get(manifest.get("mode", ""), ()):
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                failed.append(f"{module} could not be imported: {type(exc).__name__}: {exc}")
        except Exception as exc:  # any failure of another module's import is reported
            failed.append(f"{module} could not be imported: {type(exc).__name__}: {exc}")
    parts = []
    for fn in list(SECTIONS):
        try:
            part = fn(manifest, trials, out)
        except Exception as exc:  # a broken section must not cost the whole report
            failed.append(f"section {fn.__module__}.{fn.__qualname__} failed: {type(exc).__name__}: {exc}")
            continue
        if part:
            parts.append(part)
    return [*(f"<p class=err>{esc(text)}</p>" for text in failed), *parts]


OWN_FILES = ("figures/rates_by_*.png", "figures/accuracy_by_*.png", "figures/error_cdf.png", "figures/time.png",
             "figures/sky.png", "data/by_*.csv", "data/error_cdf.csv", "data/time-*.csv", "data/sky.csv",
             "data/status.csv", "data/reference-*.csv")
"""The report's own files: those a new report did not write again (an axis or a reference gone,
a figure without data) are removed once the new page is in place."""


def _remove_stale(out: Path, written: set[str]) -> None:
    for pattern in OWN_FILES:
        for path in out.glob(pattern):
            if path.relative_to(out).as_posix() not in written:
                path.unlink(missing_ok=True)


def _figures(out: Path, drawn: list[ReportFigure], notes: list[str], written: set[str]) -> str:
    parts = ["<h2>Figures</h2>", *(f"<p>{esc(note)}</p>" for note in notes)]
    for fig in drawn:
        png, csvs = save_figure(fig, out)
        written.update([png, *csvs])
        parts.append(_figure(fig, png, csvs))
    return "".join(parts)


def _reference_section(out: Path, refs: list[ReferenceTable], written: set[str]) -> str:
    csvs = [None if r.error else f"data/reference-{i}.csv" for i, r in enumerate(refs)]
    for ref, csv in zip(refs, csvs, strict=True):
        if csv is not None:
            write_csv(ref.table, out / csv)
            written.add(csv)
    return _references(refs, csvs) if refs else ""


def write_report(out: str | Path) -> Path:
    """Write the report of the campaign in folder ``out`` and return the path of ``report.html``.

    Writes ``cells.csv``, ``figures/*.png``, ``data/*.csv`` (the numbers behind every figure and
    table) and ``report.html`` (module docstring), each atomically, the page last; then removes
    the files of an earlier report that this one no longer has (:data:`OWN_FILES`). Every table
    and figure is computed before the first file is written, so a folder that cannot be reported
    is left as it was.

    Raises
    ------
    InvalidInputError
        If ``out`` is not a campaign folder, a damaged one (its manifest, a trial part), or holds
        no finished trial; nothing is written then.
    """
    out = Path(out)
    manifest, trials = read_campaign(out)
    cells, status = cell_table(trials, manifest), status_table(trials, manifest)
    drawn, notes = report_figures(trials, manifest)
    refs = reference_tables(trials, manifest, strict=False)
    head = [_head(manifest, trials), _cells(cells), _status(status)]
    tail = [_worst(trials, manifest, out), _provenance(manifest)]
    for sub in ("figures", "data"):  # the first write: everything above only reads
        (out / sub).mkdir(exist_ok=True)
    write_csv(cells, out / "cells.csv")
    write_csv(status, out / "data" / "status.csv")
    written = {"cells.csv", "data/status.csv"}
    body = [*head, _figures(out, drawn, notes, written), _reference_section(out, refs, written),
            *_extra_sections(manifest, trials, out), *tail]
    page = (f"<!DOCTYPE html><html lang=en><head><meta charset=utf-8><title>{esc(manifest.get('name', ''))}: "
            f"campaign report</title><style>{CSS}</style></head><body>{''.join(body)}</body></html>\n")
    path = out / "report.html"
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    _remove_stale(out, written)
    return path
