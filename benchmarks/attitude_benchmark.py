"""Wahba solver benchmark: every startrack solver, batched and one by one, beside scipy and ahrs.

Part 1, ``--problems`` star-tracker problems of ``--vectors`` stars each (random attitude, stars
uniform in a cone of ``--fov-deg``, isotropic noise of ``--noise-arcsec`` per axis, equal
weights): for each solver of :data:`startrack.attitude.METHODS` the solves per second batched
(one call for all problems, best of ``--repeat``) and one by one (a Python loop over the first
``--single`` problems), the median and maximum error against the truth, and the largest angle
from scipy's ``Rotation.align_vectors`` (the reference optimum) on the same problem; then
``align_vectors`` itself, one by one (it has no batched form).

Part 2, the same number of two-vector problems (two random directions, same noise) for the
``ahrs`` package, whose QUEST, Davenport and TRIAD take exactly two vector pairs: ahrs one by one
(in its own environment, ``benchmarks/.venv-ahrs``, created on first use; ``--no-peer`` skips it)
beside our batched and one-by-one solves and ``align_vectors``.

The table is printed and saved as JSON under ``benchmarks/results/``. Usage::

    python benchmarks/attitude_benchmark.py [--problems 10000] [--vectors 10] [--single 2000]
        [--noise-arcsec 10] [--fov-deg 20] [--repeat 3] [--seed 1] [--no-peer]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))

from startrack.attitude import METHODS, solve_wahba  # noqa: E402
from startrack.frames import normalize  # noqa: E402
from startrack.units import ARCSEC, DEG  # noqa: E402

RESULTS_DIR = Path(__file__).resolve().parent / "results"
HEADER = (f"{'solver':<22} {'problems':>8} {'batched /s':>11} {'single /s':>10} "
          f"{'median err':>11} {'max err':>10} {'max vs scipy':>13}")
NOTE = "errors in arcsec against the truth; 'max vs scipy' is the largest angle from align_vectors (rad)"


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=10_000)
    parser.add_argument("--vectors", type=int, default=10)
    parser.add_argument("--single", type=int, default=2000, help="problems solved one by one (rate)")
    parser.add_argument("--noise-arcsec", type=float, default=10.0)
    parser.add_argument("--fov-deg", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-peer", action="store_true", help="do not run ahrs")
    parser.add_argument("--out", type=Path, default=None)
    return parser.parse_args(argv)


def _perturb(vectors: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Unit vectors moved by isotropic small-angle noise of ``sigma`` rad per axis."""
    noise = rng.normal(scale=sigma, size=vectors.shape)
    noise -= np.sum(noise * vectors, axis=-1, keepdims=True) * vectors  # tangent part only
    return normalize(vectors + noise)


def make_problems(count: int, vectors: int, half_angle: float | None, sigma: float, rng):
    """Truth rotations and (observed, reference) (count, vectors, 3); a cone or the whole sphere."""
    truth = Rotation.random(count, random_state=rng)
    if half_angle is None:
        camera = normalize(rng.normal(size=(count, vectors, 3)))
    else:
        cos_z = rng.uniform(np.cos(half_angle), 1.0, size=(count, vectors))
        phi = rng.uniform(0, 2 * np.pi, size=(count, vectors))
        sin_z = np.sqrt(1 - cos_z**2)
        camera = np.stack([sin_z * np.cos(phi), sin_z * np.sin(phi), cos_z], axis=-1)
    reference = np.einsum("mji,mnj->mni", truth.as_matrix(), camera)
    return truth, _perturb(camera, sigma, rng), reference


def _best_time(func, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return best


def _scipy_one_by_one(observed, reference, count):
    t0 = time.perf_counter()
    rots = [Rotation.align_vectors(observed[k], reference[k])[0] for k in range(count)]
    return Rotation.concatenate(rots), time.perf_counter() - t0


def _row(name, problems, batched_s, single_s, single_n, estimate, truth, scipy_rot):
    err = (estimate * truth.inv()).magnitude() / ARCSEC
    vs = (estimate * scipy_rot.inv()).magnitude()
    return {"solver": name, "problems": problems,
            "batched_per_s": None if batched_s is None else problems / batched_s,
            "single_per_s": None if single_s is None else single_n / single_s,
            "median_err_arcsec": float(np.median(err)), "max_err_arcsec": float(np.max(err)),
            "max_vs_scipy_rad": float(np.max(vs))}


def run_ours(observed, reference, truth, scipy_rot, args, methods=METHODS, label=""):
    """One row per solver: batched and one-by-one rates, accuracy."""
    rows = []
    single = min(args.single, len(observed))
    for method in methods:
        result = solve_wahba(observed, reference, method=method)
        batched = _best_time(lambda m=method: solve_wahba(observed, reference, method=m), args.repeat)
        t0 = time.perf_counter()
        for k in range(single):
            solve_wahba(observed[k], reference[k], method=method)
        one = time.perf_counter() - t0
        rows.append(_row(f"startrack {method}{label}", len(observed), batched, one, single,
                         result.rotation, truth, scipy_rot))
    return rows


def run_ahrs(observed, reference, truth, scipy_rot) -> list[dict]:
    from peers.ahrs_env import run_ahrs as run_peer

    with tempfile.TemporaryDirectory() as tmp:
        problems = Path(tmp) / "problems.npz"
        np.savez(problems, observed=observed, reference=reference)
        out = run_peer(problems, Path(tmp) / "out.npz")
    rows = []
    for name in ("quest", "davenport", "triad"):
        rot = Rotation.from_quat(out[f"{name}_quat"])
        rows.append(_row(f"ahrs {name}", len(observed), None, float(out[f"{name}_time_s"]),
                         len(observed), rot, truth, scipy_rot))
    return rows


def _fmt(value, spec):
    return f"{'-':>{spec}}" if value is None else f"{value:>{spec}.{'0f' if spec > 9 else '3g'}}"


def print_table(title: str, rows: list[dict]) -> None:
    print(f"\n{title}\n{HEADER}")
    for r in rows:
        print(f"{r['solver']:<22} {r['problems']:>8} {_fmt(r['batched_per_s'], 11)} "
              f"{_fmt(r['single_per_s'], 10)} {r['median_err_arcsec']:>11.3f} "
              f"{r['max_err_arcsec']:>10.3f} {r['max_vs_scipy_rad']:>13.2e}")
    print(NOTE)


def part(title, truth, observed, reference, args, peer: bool) -> list[dict]:
    scipy_rot, scipy_s = _scipy_one_by_one(observed, reference, len(observed))
    rows = run_ours(observed, reference, truth, scipy_rot, args)
    rows.append(_row("scipy align_vectors", len(observed), None, scipy_s, len(observed),
                     scipy_rot, truth, scipy_rot))
    if peer:
        rows += run_ahrs(observed, reference, truth, scipy_rot)
    print_table(title, rows)
    return rows


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    rng = np.random.default_rng(args.seed)
    sigma = args.noise_arcsec * ARCSEC
    print(f"load average {os.getloadavg()[0]:.2f}; {args.problems} problems, noise {args.noise_arcsec} arcsec")
    truth, observed, reference = make_problems(args.problems, args.vectors, 0.5 * args.fov_deg * DEG, sigma, rng)
    rows = part(f"Part 1: {args.vectors} stars in a {args.fov_deg:g} deg field", truth, observed, reference,
                args, peer=False)
    truth2, observed2, reference2 = make_problems(args.problems, 2, None, sigma, rng)
    rows2 = part("Part 2: two vector pairs (random directions), with ahrs", truth2, observed2, reference2,
                 args, peer=not args.no_peer)
    quest = next(r for r in rows if r["solver"] == "startrack quest")
    scipy = next(r for r in rows if r["solver"] == "scipy align_vectors")
    print(f"\nbatched QUEST / one-by-one align_vectors: {quest['batched_per_s'] / scipy['single_per_s']:.1f}x "
          f"(target >= 10x); load average {os.getloadavg()[0]:.2f}")
    out = args.out or RESULTS_DIR / f"attitude-{datetime.now():%Y%m%d-%H%M%S}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"args": vars(args), "part1": rows, "part2": rows2}, indent=1, default=str))
    print(f"results saved to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
