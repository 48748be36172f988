"""The solvers a lost-in-space benchmark compares, each behind one call on a batch of star lists.

:func:`solve_ours` calls ``startrack.solve_stars`` in this process; :func:`solve_cedar` writes the
lists to an ``.npz`` and runs cedar-solve in its own environment (``peers/cedar_env.py``). Both
time each solve with ``time.perf_counter`` around the solver call alone, after one untimed
warm-up solve, and return a :class:`MethodRun` judged by :mod:`scoring` the same way.

What each solver is told about the field of view (:class:`FovKnowledge`):

- known FOV ``f``: ours gets ``fov_deg=f`` (which it trusts to +-3 %, ``FOV_DEG_TOLERANCE`` in
  ``startrack.solve``, and refines); cedar gets ``fov_estimate=f`` and
  ``fov_max_error=0.03 * f``, the same bound;
- a range ``(lo, hi)``: ours gets ``fov_range_deg=(lo, hi)``; cedar gets
  ``fov_estimate=(lo + hi) / 2`` and ``fov_max_error=(hi - lo) / 2``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from startrack import solve_stars
from startrack.analysis._scoring import rotations_from_radec_roll_deg
from startrack.analysis._starlists import Conditions, StarList

try:
    from startrack.solve import FOV_DEG_TOLERANCE as KNOWN_FOV_TOLERANCE
except ImportError:  # the solver is not there yet: its documented tolerance
    KNOWN_FOV_TOLERANCE = 0.03


@dataclass(frozen=True)
class FovKnowledge:
    """What a solver is told about the field of view: a value, a range, or (neither) nothing."""

    fov_deg: float | None = None
    fov_range_deg: tuple[float, float] | None = None

    @property
    def label(self) -> str:
        if self.fov_deg is not None:
            return "known FOV"
        if self.fov_range_deg is not None:
            return f"FOV {self.fov_range_deg[0]:g}-{self.fov_range_deg[1]:g}"
        return "no FOV"

    def ours_kwargs(self) -> dict:
        """Keyword arguments for ``startrack.solve_stars``."""
        if self.fov_deg is not None:
            return {"fov_deg": float(self.fov_deg)}
        if self.fov_range_deg is not None:
            return {"fov_range_deg": tuple(float(v) for v in self.fov_range_deg)}
        return {}

    def cedar_estimate(self) -> tuple[float | None, float | None]:
        """``(fov_estimate, fov_max_error)`` in degrees for tetra3's ``solve_from_centroids``."""
        if self.fov_deg is not None:
            return float(self.fov_deg), KNOWN_FOV_TOLERANCE * float(self.fov_deg)
        if self.fov_range_deg is not None:
            lo, hi = self.fov_range_deg
            return 0.5 * (lo + hi), 0.5 * (hi - lo)
        return None, None


@dataclass
class MethodRun:
    """One method's answers on a batch of lists: solved flags, attitudes, times (s)."""

    method: str
    solved: NDArray[np.bool_]
    estimates: list[Rotation | None]
    time_s: NDArray[np.float64]
    extra: dict = field(default_factory=dict)


def concatenate_runs(runs: list[MethodRun]) -> MethodRun:
    """One method's runs on consecutive chunks of lists as one run: per-list arrays of ``extra``
    are joined, anything else (a database description) is taken from the first chunk."""
    first = runs[0]
    extra = {key: (np.concatenate([r.extra[key] for r in runs]) if isinstance(value, np.ndarray) else value)
             for key, value in first.extra.items()}
    return MethodRun(first.method, np.concatenate([r.solved for r in runs]),
                     [e for r in runs for e in r.estimates], np.concatenate([r.time_s for r in runs]), extra)


CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}
"""How a solve is timed: wall clock, or the CPU time of the solving thread."""


def solve_ours(lists: list[StarList], conditions: Conditions, knowledge: FovKnowledge,
               *, matcher: str = "quads", warmup: bool = True, progress: int = 0,
               timeout_s: float | None = None, clock: str = "wall") -> MethodRun:
    """Solve every list with ``startrack.solve_stars(method=matcher)`` (in this process), with the
    matcher's default time limit or ``timeout_s``, each timed by ``clock`` (:data:`CLOCKS`)."""
    from startrack.identify._registry import options_for

    options = None if timeout_s is None else options_for(matcher, timeout_s=timeout_s)
    kwargs = dict(width=conditions.width, height=conditions.height, epoch=conditions.epoch_jyear,
                  method=matcher, options=options, **knowledge.ours_kwargs())
    if warmup and lists:
        solve_stars(lists[0].x, lists[0].y, flux=lists[0].flux, **kwargs)
    solved = np.zeros(len(lists), dtype=bool)
    times = np.zeros(len(lists))
    estimates: list[Rotation | None] = []
    for i, star_list in enumerate(lists):
        if progress and i and i % progress == 0:
            print(f"  startrack {i}/{len(lists)}", file=sys.stderr, flush=True)
        t0 = CLOCKS[clock]()
        sol = solve_stars(star_list.x, star_list.y, flux=star_list.flux, **kwargs)
        times[i] = CLOCKS[clock]() - t0
        solved[i] = bool(sol.status)
        estimates.append(sol.rot_cam_from_icrs if solved[i] else None)
    name = "startrack" if matcher == "quads" else f"st-{matcher}"
    return MethodRun(name, solved, estimates, times)


def solve_cedar(lists: list[StarList], conditions: Conditions, knowledge: FovKnowledge,
                *, timeout_ms: float = 5000.0, progress: int = 0,
                workdir: Path | None = None, clock: str = "wall") -> MethodRun:
    """Solve every list with cedar-solve in its own environment (created on first use)."""
    from peers.cedar_env import run_cedar

    estimate, max_error = knowledge.cedar_estimate()
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        lists_npz = save_for_peer(lists, Path(tmp) / "lists.npz", width=conditions.width,
                                  height=conditions.height, fov_estimate_deg=estimate,
                                  fov_max_error_deg=max_error)
        out = run_cedar(lists_npz, Path(tmp) / "cedar.npz", solve_timeout_ms=timeout_ms,
                         progress=progress, clock=clock)
    estimates = rotations_from_radec_roll_deg(out["ra_deg"], out["dec_deg"], out["roll_deg"])
    extra = {k: out[k] for k in ("ra_deg", "dec_deg", "roll_deg", "fov_deg", "status")}
    extra["database"] = out["database"]
    return MethodRun("cedar-solve", out["solved"].astype(bool), estimates, out["time_s"], extra)


def save_for_peer(lists: list[StarList], path: Path, *, width: int, height: int,
                  fov_estimate_deg: float | None, fov_max_error_deg: float | None) -> Path:
    """Write the lists as the ``.npz`` that ``peers/cedar_runner.py`` reads (x, y back to back)."""
    n = len(lists)
    offsets = np.concatenate([[0], np.cumsum([len(s) for s in lists])]).astype(np.int64)
    np.savez(
        path,
        x=np.concatenate([s.x for s in lists]) if n else np.zeros(0),
        y=np.concatenate([s.y for s in lists]) if n else np.zeros(0),
        offsets=offsets,
        width=np.full(n, width, dtype=np.int64),
        height=np.full(n, height, dtype=np.int64),
        fov_estimate_deg=np.full(n, np.nan if fov_estimate_deg is None else fov_estimate_deg),
        fov_max_error_deg=np.full(n, np.nan if fov_max_error_deg is None else fov_max_error_deg),
    )
    return Path(path)
