"""The closed loop of Sease 2013 ch. 5 with each feedback source: metrics side by side with the
seed's, and where the wall time of a run goes.

    python benchmarks/adcs_benchmark.py [--duration-s 700] [--feedback truth imu tracker]
                                        [--law lqr] [--frame-rate-hz 5] [--model] [--pd]

Runs the seed's scenario (seven +0.1 steps in q2, one every 100 s) once per feedback source and
prints one table of the overall metrics (worst step; average power over the run) with the seed's
Table 5.3 and power figures, and one of the wall time: total, rendering the star images (the
simulated world), processing them (detection + Tracker: the star tracker's own latency) and the
rest (plant integration, planning, control), and the process CPU time (steadier than the wall
time when other jobs share the cores). ``--model`` adds a run with the noise model fitted
from the tracker run; ``--pd`` adds the PD baseline with the truth and the tracker. Wall-clock
times on a 2-core machine shared with other jobs: compare runs made together.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from startrack.adcs._loop import LoopConfig, run_loop
from startrack.adcs._metrics import METRIC_KEYS, SEED_POWER_W, SEED_TABLE_5_3, run_metrics
from startrack.adcs._scenario import Scenario
from startrack.adcs._star_tracker_feedback import StarTrackerSetup, fit_noise_model

HEADS = ("ss err deg", "overshoot %", "rise s", "settle s", "avg W", "peak W")
DIGITS = (4, 2, 2, 2, 4, 3)


def _row(label: str, overall) -> str:
    cells = [getattr(overall, k) for k in METRIC_KEYS]
    return f"| {label} | " + " | ".join(f"{v:.{d}f}" for v, d in zip(cells, DIGITS, strict=True)) + " |"


def _time_row(label: str, record, total_s: float, cpu_s: float) -> str:
    render = sum(f.render_s for f in record.frames)
    proc = sum(f.processing_s for f in record.frames if np.isfinite(f.processing_s))
    frames = len(record.frames)
    per = f"{1e3 * proc / frames:.1f} ms" if frames and proc else "-"
    return (f"| {label} | {total_s:.1f} s | {cpu_s:.1f} s | {record.wall_s:.1f} s | {render:.1f} s | "
            f"{proc:.1f} s ({per}/frame) | {record.wall_s - render - proc:.1f} s | {frames} |")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--duration-s", type=float, default=700.0)
    p.add_argument("--feedback", nargs="+", default=["truth", "imu", "tracker"])
    p.add_argument("--law", default="lqr")
    p.add_argument("--frame-rate-hz", type=float, default=5.0)
    p.add_argument("--model", action="store_true", help="add the fitted tracker noise model")
    p.add_argument("--pd", action="store_true", help="add the PD baseline (truth and tracker)")
    args = p.parse_args(argv)
    scenario = Scenario(duration_s=args.duration_s)
    setup = StarTrackerSetup(frame_rate_hz=args.frame_rate_hz)
    runs = [(fb, LoopConfig(feedback=fb, law=args.law, scenario=scenario, tracker=setup)) for fb in args.feedback]
    if args.pd:
        runs += [(f"{fb} (PD)", LoopConfig(feedback=fb, law="pd", scenario=scenario, tracker=setup))
                 for fb in ("truth", "tracker")]
    results = []
    for label, config in runs:
        start, cpu = time.perf_counter(), time.process_time()
        record = run_loop(config)
        results.append((label, record, time.perf_counter() - start, time.process_time() - cpu))
        print(f"ran {label}: {record.wall_s:.1f} s", file=sys.stderr)
        if args.model and config.feedback == "tracker" and config.law == "lqr":
            model = fit_noise_model(record.frames, record.t_s, record.omega_true)
            start, cpu = time.perf_counter(), time.process_time()
            modelled = run_loop(LoopConfig(feedback="tracker-model", noise_model=model, law=args.law,
                                           scenario=scenario, tracker=setup))
            results.append(("tracker-model", modelled, time.perf_counter() - start, time.process_time() - cpu))
    print(f"\n{args.duration_s:g} s, seven +0.1 steps in q2, {args.law.upper()} law, star tracker at "
          f"{args.frame_rate_hz:g} Hz\n")
    print("| feedback | " + " | ".join(HEADS) + " |\n|" + " --- |" * (len(HEADS) + 1))
    for label, record, *_ in results:
        print(_row(label, run_metrics(record)[1]))
    s, w = SEED_TABLE_5_3, SEED_POWER_W
    print(f"| Sease 2013 Table 5.3 (hardware) | < {s['steady_state_error_deg']} | < {s['overshoot_pct']} | "
          f"< {s['rise_time_s']} | < {s['settling_time_s']} | ~{w['avg_power_w']} (PID {w['pid_avg_power_w']}) | "
          f"~{w['peak_power_w']} |")
    print("\n| feedback | wall (with set-up) | CPU | loop wall | rendering images | detect + track | "
          "plant, plans, control | frames |\n|" + " --- |" * 8)
    for label, record, total, cpu in results:
        print(_time_row(label, record, total, cpu))
    return 0


if __name__ == "__main__":
    sys.exit(main())
