"""Seed reproductions for streaked and smeared images, run as campaigns, ours beside the seeds'.

Each part runs a shipped spec (``startrack/analysis/campaign/specs/``) through the campaign
engine (``seed_campaign.py``) and prints its reference tables; the per-trial logic lives in the
campaign levels ``streak``, ``rso`` and ``smear`` (``startrack.analysis.campaign.levels``) and the
scenes in ``startrack.analysis._streak_scenes`` / ``startrack.analysis._rso_passes``. Conditions
and results: ``docs/seed_tables_sease_samaan.md``.

1. Sease 2013 Table 3.1 (``sease2013-table3.1-streak-endpoints``): endpoint error (px) and rate
   error (% of |omega|) of the Harris, minimum-eigenvalue, Trajkovic-4 and Trajkovic-8 endpoint
   detectors at 10 % and 50 % streak length, spin axes 30-90 deg from the boresight, each
   detector's bias calibrated on separate frames.
2. Sease 2013 Tables 4.1 and 4.2 (``sease2013-tables4.1-4.2-catalog-free-rate``): catalog-free rate,
   T = 0.5 s, 2 deg/s and 0.05 rad/s about the camera y axis, with and without an Mv-1 RSO.
3. Sease 2013 Tables 4.3 and 4.4 (``sease2013-tables4.3-4.4-rso-detection``): RSO detections of the
   three indicators over the observation opportunities of the Table 4.3 orbits.
4. Samaan 2002 Table 2 (``samaan2002-table2-smear-centroids``): centroid error against smear
   (interstar-angle sigma and image-plane STD, microradians), StarNav I (512 x 512, 8 deg).
5. Issue 19, streak mode on ordinary catalog frames (``streak-mode``): whole sky, 12 and 20 deg
   fields, 1024 x 1024, 0.5-8 deg/s about random axes, streaks of 5-30 % of the field: the share
   solved lost-in-space, the rate and axis errors of the trusted rates beside the Sease 2013 targets,
   the frames with at least 5 identified streaks that meet the target, the time per frame, and a
   list of those that miss it (:func:`print_streak_misses`).
6. Issue 19, the Tracker through a slew (:func:`run_slew`): the simulator's sequence
   (:func:`startrack.simulate.simulate_sequence`, 1024 x 1024, 20 deg, generic CMOS, 0.1 s
   exposures at 5 frames a second) of a rate that rests 1 s, speeds up to 8 deg/s in 2 s, holds
   1 s, slows down in 2 s and rests 1 s: every frame's mode, attitude error and rate error, and
   where the mode switched.
7. Issue 19, the speed of the streak ends (:func:`run_end_speed`): on 1024 x 1024 frames (12 deg)
   of 20 streaks 30 and 150 px long, the process time of the streak path's search and fit
   (``streak_find`` + ``streak_fit``) against the segmentation of :mod:`startrack.rate.
   streak_detect` with Harris corners and with the earlier blurred-segment fit (best of 3; the
   issue: no slower than 5x Harris).

Usage::

    python benchmarks/streak_benchmark.py [--parts 1,2,3,4,5,6,7] [--frames 6] [--rso-trials 1]
        [--smear-images 30] [--streak-frames 100] [--seed S] [--slew-glow E] [--workers 2 | --sync] [--out DIR]
        [--json PATH]

``--frames`` sets the frames per cell of parts 1 and 2, ``--rso-trials`` the star fields per
opportunity of part 3, ``--smear-images`` the images per cell of part 4, ``--streak-frames`` the
frames per condition of part 5 (the specs' own defaults are 20, 10, 1, 100 and 100); ``--seed``
replaces every spec's campaign seed. Part 5's time per frame is printed as wall time and as
process time: on a shared machine the wall time holds the waits for a core.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))

from seed_campaign import add_run_arguments, out_for, print_references, run_spec, spec_text  # noqa: E402

from startrack.analysis.campaign._aggregate import read_campaign  # noqa: E402
from startrack.analysis.campaign._reference import reference_tables  # noqa: E402

RESULTS_DIR = ROOT / "results"
PARTS = {
    1: ("sease2013-table3.1-streak-endpoints", "frames"),
    2: ("sease2013-tables4.1-4.2-catalog-free-rate", "frames"),
    3: ("sease2013-tables4.3-4.4-rso-detection", "rso_trials"),
    4: ("samaan2002-table2-smear-centroids", "smear_images"),
    5: ("streak-mode", "streak_frames"),
}
SLEW_PART, SPEED_PART = 6, 7
"""Part -> (shipped spec, the option that sets its trials per cell)."""


MISS_COLUMNS = ("fov_deg", "rate_deg_s", "n_matched", "streak_px", "rate_status", "rate_err_any_pct", "axis_err_deg",
                "rate_sigma3_pct", "rate_sigma_roll_deg_s", "rate_sigma_cross_deg_s", "birge", "rate_bound_pct",
                "target_chance")


def print_streak_misses(trials) -> list[dict]:
    """Part 5: list the frames with at least 5 identified streaks that miss the issue's target (a
    trusted rate within 1 % and an axis within 0.5 deg): their streak count and length, the
    rate's status, its error (trusted or not) and the 3-sigma and roll / cross 1-sigma the solver
    claims (% of the rate); returns them as rows."""
    import numpy as np

    from startrack.analysis.campaign._aggregate import as_columns

    cols = as_columns(trials)
    if not {"five_streaks", "meets_target"} <= set(cols) or not set(MISS_COLUMNS) <= set(cols):
        return []
    miss = np.flatnonzero(cols["five_streaks"].astype(bool) & ~cols["meets_target"].astype(bool))
    rows = [{k: (v.item() if hasattr(v, "item") else v) for k, v in ((c, cols[c][i]) for c in MISS_COLUMNS)}
            for i in miss]
    print(f"\nframes with at least 5 identified streaks that miss the target ({len(rows)} of "
          f"{int(cols['five_streaks'].astype(bool).sum())}): sigmas are the solver's, % of the rate; bound: the "
          "Cramer-Rao 1-sigma of the rate vector at the true state, % of the rate; chance: that an efficient "
          "estimator of these streaks meets the target")
    print(f"  {'fov':>4} {'deg/s':>5} {'streaks':>7} {'length px':>9} {'rate status':>13} {'err %':>6} {'axis deg':>8} "
          f"{'3 sigma %':>9} {'roll 1s %':>9} {'cross 1s %':>10} {'birge':>5} {'bound %':>7} {'chance':>6}")
    for r in rows:
        speed = r["rate_deg_s"]
        print(f"  {r['fov_deg']:4.0f} {speed:5.1f} {r['n_matched']:7d} {r['streak_px']:9.0f} {r['rate_status']:>13} "
              f"{r['rate_err_any_pct']:6.2f} {r['axis_err_deg']:8.2f} {r['rate_sigma3_pct']:9.2f} "
              f"{100 * r['rate_sigma_roll_deg_s'] / speed:9.2f} {100 * r['rate_sigma_cross_deg_s'] / speed:10.2f} "
              f"{r['birge']:5.2f} {r['rate_bound_pct']:7.2f} {r['target_chance']:6.2f}")
    if "target_chance_trusted" in cols:
        five = cols["five_streaks"].astype(bool)
        ideal = float(np.nansum(1.0 - cols["target_chance"][five]))
        refusing = float(np.nansum(1.0 - cols["target_chance_trusted"][five]))
        print(f"  misses expected of an efficient unbiased estimator of the same streaks: {ideal:.1f} of {five.sum()}, "
              f"{refusing:.1f} when it also refuses a 3-sigma bound over the trust limit; ours: {len(rows)}")
        claimed = cols["rate_sigma3_pct"][five] / (3.0 * cols["rate_bound_pct"][five])
        spread = cols["rate_err_any_pct"][five] / cols["rate_bound_pct"][five]
        print(f"  the solver's 3-sigma over the bound's: median {np.nanmedian(claimed):.3f}; its rate error over the "
              f"bound: median {np.nanmedian(spread):.2f}, 95th percentile {np.nanpercentile(spread, 95):.2f}")
    return rows


def run_part(part: int, args: argparse.Namespace) -> dict:
    """Run one part's spec and print its reference tables; returns them as plain data."""
    name, option = PARTS[part]
    print(f"\npart {part}: {name}", flush=True)
    text = spec_text(name, trials=getattr(args, option), seed=args.seed)
    _, out, _ = run_spec(text, out_for(args, name), args.workers, args.sync)
    print_references(out)
    manifest, trials = read_campaign(out)
    misses = print_streak_misses(trials) if name == PARTS[5][0] else None
    return {"misses": misses,
            "spec": name, "out": str(out), "trials_per_cell": manifest["trials_per_cell"],
            "references": [{"title": r.title, "metric": r.metric, "unit": r.unit, "rows": r.table.to_pylist()}
                           for r in reference_tables(trials, manifest, strict=False)]}


SLEW = {"size_px": 1024, "fov_deg": 20.0, "exposure_s": 0.1, "frame_rate_hz": 5.0, "peak_deg_s": 8.0,
        "rest_s": 1.0, "ramp_s": 2.0, "hold_s": 1.0, "seed": 19}
SLEW_AXIS = (0.3, -0.9, 0.2)


def slew_rate(t_s):
    """The slew's camera-frame rate (rad/s, (N, 3)) at times ``t_s`` (part 6)."""
    import numpy as np

    axis = np.asarray(SLEW_AXIS) / np.linalg.norm(SLEW_AXIS)
    t = np.asarray(t_s, dtype=float) - SLEW["rest_s"]
    ramp, top = SLEW["ramp_s"], 2 * SLEW["ramp_s"] + SLEW["hold_s"]
    speed = np.radians(SLEW["peak_deg_s"]) * np.clip(np.minimum(t / ramp, (top - t) / ramp), 0.0, 1.0)
    return speed[:, None] * axis[None, :]


def run_slew(glow_e: float = 0.0) -> dict:
    """Part 6: the Tracker through the slew (module docstring); prints a row per frame and the
    switches. ``glow_e``: a limb's glow added to every frame with its shot noise, that many
    electrons at the bottom edge falling by e over 150 px (``--slew-glow``)."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from startrack import Camera
    from startrack.frames import attitude_error
    from startrack.simulate import VaryingRate, get_sensor_preset, simulate_sequence
    from startrack.track import Tracker
    from startrack.units import ARCSEC, DEG

    print(f"\npart {SLEW_PART}: the Tracker through a slew to {SLEW['peak_deg_s']:g} deg/s and back "
          f"({', '.join(f'{k} {v:g}' for k, v in SLEW.items())}, limb glow {glow_e:g} e-)", flush=True)
    from streak_glow import glow as added_light

    size, rng = SLEW["size_px"], np.random.default_rng(0)
    glow = added_light("limb", glow_e, (size, size))
    camera = Camera.from_fov(size, size, SLEW["fov_deg"])
    profile = VaryingRate(Rotation.from_euler("zyx", [40, 20, 10], degrees=True), slew_rate)
    n = int(round((2 * (SLEW["rest_s"] + SLEW["ramp_s"]) + SLEW["hold_s"]) * SLEW["frame_rate_hz"])) + 1
    frames = simulate_sequence(camera, profile, n, frame_rate_hz=SLEW["frame_rate_hz"], max_mag=7.5,
                               sensor=get_sensor_preset("generic-cmos").with_exposure(SLEW["exposure_s"]),
                               seed=SLEW["seed"], catalog_epoch_jyear=2025.0)
    tracker = Tracker(width=size, height=size, fov_deg=SLEW["fov_deg"], epoch=2025.0)
    print(f"  {tracker.smear_limits(SLEW['exposure_s'], size, size).describe()}")
    print(f"  {'frame':>5} {'t (s)':>6} {'deg/s':>6} {'mode':>7} {'step':>22} {'status':>13} {'err (arcsec)':>12} "
          f"{'rate err %':>10} {'smear px':>8} {'ms':>6}")
    rows, switches = [], []
    for k, sim in enumerate(frames):
        t = sim.truth.t_mid_s
        image = np.clip(sim.image + rng.poisson(glow), 0, 65535).astype(sim.image.dtype) if glow_e else sim.image
        step = tracker.update_image(image, t, streak_exposure_s=SLEW["exposure_s"])
        true = slew_rate([t])[0]
        speed = float(np.linalg.norm(true))
        err = attitude_error(sim.truth.rot_cam_from_icrs, step.rot_cam_from_icrs) / ARCSEC if step.status \
            else float("nan")
        rate_err = 100 * float(np.linalg.norm(step.rate_rad_s - true)) / speed \
            if step.rate_rad_s is not None and speed > 0 else float("nan")
        row = {"frame": k, "t_s": t, "rate_deg_s": speed / DEG, "mode": tracker.mode, "step": step.mode,
               "status": step.status.name, "err_arcsec": err, "rate_err_pct": rate_err,
               "smear_px": step.extra.get("streak_px", float("nan")), "ms": 1e3 * step.time_s}
        rows.append(row)
        print(f"  {k:5d} {t:6.2f} {speed / DEG:6.2f} {tracker.mode:>7} {step.mode:>22} {step.status.name:>13} "
              f"{err:12.1f} {rate_err:10.2f} {row['smear_px']:8.1f} {row['ms']:6.0f}", flush=True)
        if step.extra.get("switched"):
            switches.append(f"frame {k} (t = {t:.2f} s, {speed / DEG:.2f} deg/s, smear {row['smear_px']:.1f} px): "
                            f"-> {tracker.mode} mode")
    solved = [r for r in rows if r["status"] == "OK"]
    print("  mode switches:\n    " + "\n    ".join(switches or ["none"]))
    print(f"  {len(solved)} of {len(rows)} frames have an attitude; error median "
          f"{np.median([r['err_arcsec'] for r in solved]):.1f} arcsec, largest "
          f"{max(r['err_arcsec'] for r in solved):.1f} arcsec; time per frame median "
          f"{np.median([r['ms'] for r in rows[1:]]):.0f} ms (after the first)")
    return {"slew": SLEW, "rows": rows, "switches": switches}


def _best_cpu_s(run, repeats: int = 3):
    """(best process time over ``repeats`` calls (s), the last call's result)."""
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.process_time()
        out = run()
        best = min(best, time.process_time() - t0)
    return best, out


def run_end_speed() -> dict:
    """Part 7: process time of the streak ends, the streak path against Harris and the segment fit."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from startrack import Camera
    from startrack.analysis._streak_scenes import render_streak_scene, spin_rate, star_field
    from startrack.rate import _streak_rate as streak_rate
    from startrack.rate._streak_detect import find_streaks
    from startrack.rate._streak_find import find_streak_candidates
    from startrack.rate._streak_fit import first_guesses, fit_streaks
    from startrack.units import DEG

    print(f"\npart {SPEED_PART}: streak ends, process time (ms, best of 3) on 1024 x 1024 px, 12 deg, 20 streaks",
          flush=True)
    camera, rows = Camera.from_fov(1024, 1024, 12.0), []
    print(f"  {'length':>6} {'streak path':>11} {'(ok)':>5} {'segmentation':>12} {'+ Harris':>8} {'+ segment fit':>13} "
          f"{'path / Harris':>13} {'segment / Harris':>16}")
    for length in (30, 150):
        rng = np.random.default_rng(1)
        omega = spin_rate(90 * DEG, 2 * DEG, 0.3)
        exposure = length / camera.fx / (2 * DEG)
        vectors = star_field(camera, omega, exposure, 20, rng, margin_px=15)
        image = render_streak_scene(camera, Rotation.random(random_state=rng), omega, exposure, vectors,
                                    rng.uniform(2e4, 1e5, 20), rng=rng).image

        def path(img=image):
            cand = find_streak_candidates(img)
            start, own, reach, band = first_guesses(img, cand)
            return fit_streaks(img, start, reach, band, noise=cand.noise, labels=cand.labels, bin_px=cand.bin_px,
                               own=own)

        def harris(img=image):
            return streak_rate._corner_ends(img, find_streaks(img), "harris", 0.64, 6.0, streak_rate.LENGTH_TOLERANCE,
                                            None)

        def segment(img=image):
            return streak_rate._segment_ends(img, find_streaks(img), 6.0)

        t_path, fits = _best_cpu_s(path)
        t_seg_only, _ = _best_cpu_s(lambda img=image: find_streaks(img))
        t_harris, _ = _best_cpu_s(harris)
        t_segment, _ = _best_cpu_s(segment)
        row = {"length_px": length, "path_ms": 1e3 * t_path, "ok": int(fits.ok.sum()),
               "segmentation_ms": 1e3 * t_seg_only, "harris_ms": 1e3 * t_harris, "segment_fit_ms": 1e3 * t_segment}
        rows.append(row)
        print(f"  {length:6d} {row['path_ms']:11.0f} {row['ok']:5d} {row['segmentation_ms']:12.0f} "
              f"{row['harris_ms']:8.0f} {row['segment_fit_ms']:13.0f} {t_path / t_harris:13.2f} "
              f"{t_segment / t_harris:16.2f}", flush=True)
    return {"rows": rows}


def run_any(part: int, args: argparse.Namespace) -> dict:
    """One part: a spec (1-5), the slew (6) or the speed of the ends (7)."""
    if part == SLEW_PART:
        return run_slew(args.slew_glow)
    if part == SPEED_PART:
        return run_end_speed()
    return run_part(part, args)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=str, default="1,2,3,4,5,6,7", help="comma-separated parts to run (1-7)")
    parser.add_argument("--frames", type=int, default=6, help="frames per cell of parts 1 and 2")
    parser.add_argument("--rso-trials", type=int, default=1, help="star fields per opportunity of part 3")
    parser.add_argument("--smear-images", type=int, default=30, help="images per cell of part 4 (seed: 100)")
    parser.add_argument("--streak-frames", type=int, default=100, help="frames per condition of part 5")
    parser.add_argument("--seed", type=int, default=None, help="campaign seed of every part (default: the specs')")
    parser.add_argument("--slew-glow", type=float, default=0.0,
                        help="part 6: a limb's glow added to every frame, e- at the bottom edge (default 0)")
    parser.add_argument("--json", type=Path, default=None, help="where to save the tables (default: results/)")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    try:
        parts = sorted({int(p) for p in args.parts.split(",")})
    except ValueError:
        parser.error(f"--parts: comma-separated numbers 1-4, got {args.parts!r}")
    if not set(parts) <= set(PARTS) | {SLEW_PART, SPEED_PART}:
        parser.error(f"--parts: valid parts are 1-7, got {args.parts!r}")
    t0 = time.perf_counter()
    results = {"args": {k: str(v) if isinstance(v, Path) else v for k, v in vars(args).items()},
               "parts": {part: run_any(part, args) for part in parts}}
    path = args.json or RESULTS_DIR / f"streak-{datetime.now():%Y%m%d-%H%M%S}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=1, default=str))
    print(f"\nfinished in {time.perf_counter() - t0:.0f} s; tables saved to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
