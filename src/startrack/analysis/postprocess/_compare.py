"""Analysis 8: two result sets side by side, image by image (matched by record name), with their
differences: solved or not, the angle between the two boresights (arcsec), the roll difference
(the z component of the rotation ``b * a^-1`` in the camera frame, arcsec), the total angle
between the attitudes, matches and rms residuals (Fowler 2013 Ch.8 "batch comparison of result
sets", e.g. lens on against off).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...frames import angle_between, boresight
from ...units import ARCSEC
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import new_figure, no_data
from ._ground import error_arcsec

INFO = AnalysisInfo(
    name="compare",
    title="Two result sets side by side",
    description="The images of two result sets matched by name: solved in each, the angle between the "
                "two boresights and the roll difference (arcsec), matches and rms residuals, and which "
                "images are in one set only.",
    min_sets=2, max_sets=2,
)
COLUMNS = ("record", "in_a", "in_b", "solved_a", "solved_b", "pointing_diff_arcsec", "roll_diff_arcsec",
           "total_diff_arcsec", "matches_a", "matches_b", "residual_a_arcsec", "residual_b_arcsec")


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    a, b = ({r.name: r for r in s.records} for s in sets)
    names = list(a) + [n for n in b if n not in a]
    table: dict[str, list] = {k: [] for k in COLUMNS}
    for name in names:
        for key, value in zip(COLUMNS, _row(name, a.get(name), b.get(name)), strict=True):
            table[key].append(value)
    fig = _draw(table, sets[0].name, sets[1].name)
    return AnalysisResult(INFO.name, INFO.title, fig, {"images": table}, _summary(table, sets))


def _row(name: str, ra, rb) -> tuple:
    sa, sb = (r is not None and r.solution.solved for r in (ra, rb))
    pointing = roll = total = float("nan")
    if sa and sb:
        rot_a, rot_b = ra.solution.rot_cam_from_icrs, rb.solution.rot_cam_from_icrs
        pointing = float(angle_between(boresight(rot_a), boresight(rot_b)) / ARCSEC)
        total, _, roll = error_arcsec(rot_b, rot_a)
    return (name, ra is not None, rb is not None, sa, sb, pointing, roll, total, _matches(ra), _matches(rb),
            _rms(ra), _rms(rb))


def _matches(record) -> int:
    return len(record.solution.matches) if record is not None and record.solution.solved else 0


def _rms(record) -> float:
    if record is None or not record.solution.solved:
        return float("nan")
    return float(np.sqrt(np.mean(record.solution.residuals_arcsec**2)))


def _draw(table: dict[str, list], name_a: str, name_b: str):
    fig, axes = new_figure(1, 3, width_in=4.2, height_in=3.6, title=f"{INFO.title}: {name_a} (a) and {name_b} (b)")
    x = np.arange(len(table["record"]))
    both = np.asarray(table["solved_a"], bool) & np.asarray(table["solved_b"], bool)
    ax = axes[0, 0]
    if both.any():
        ax.bar(x[both] - 0.2, np.asarray(table["pointing_diff_arcsec"])[both], width=0.4, label="pointing")
        ax.bar(x[both] + 0.2, np.abs(np.asarray(table["roll_diff_arcsec"]))[both], width=0.4, label="|roll|")
        ax.set_ylabel("difference b - a, arcsec")
        ax.legend(fontsize=8)
    else:
        no_data(ax, "no image solved in both")
    for ax, (ka, kb, label) in zip(axes[0, 1:], (("matches_a", "matches_b", "matched stars"),
                                                  ("residual_a_arcsec", "residual_b_arcsec", "rms residual, arcsec")),
                                   strict=True):
        ax.bar(x - 0.2, np.asarray(table[ka], float), width=0.4, label=f"a: {name_a}")
        ax.bar(x + 0.2, np.asarray(table[kb], float), width=0.4, label=f"b: {name_b}")
        ax.set_ylabel(label)
        ax.legend(fontsize=8)
    for ax in axes[0]:
        ax.set_xlabel("image (in the order of the table)")
    return fig


def _summary(table: dict[str, list], sets) -> dict[str, float | int | str]:
    sa, sb = np.asarray(table["solved_a"], bool), np.asarray(table["solved_b"], bool)
    pointing = np.asarray(table["pointing_diff_arcsec"], float)[sa & sb]
    roll = np.asarray(table["roll_diff_arcsec"], float)[sa & sb]
    return {"images": len(table["record"]), "in both": int(sum(a and b for a, b in zip(table["in_a"], table["in_b"],
                                                                                       strict=True))),
            f"solved in a ({sets[0].name})": int(sa.sum()), f"solved in b ({sets[1].name})": int(sb.sum()),
            "solved in both": int((sa & sb).sum()),
            "median pointing difference, arcsec": float(np.median(pointing)) if pointing.size else float("nan"),
            "median |roll difference|, arcsec": float(np.median(np.abs(roll))) if roll.size else float("nan")}
