"""startrack adcs-demo: closed-loop attitude control of Sease 2013's KnightCube (ch. 5) with the
truth, an IMU or startrack itself in the loop. Seven steps of +0.1 in q2, one every 100 s, are
planned for minimum coil energy (virtual motion camouflage on LGL nodes, SLSQP, replanned every
5 s) and tracked at 40 Hz by an input-output-linearised LQR (Q = 20 I, R = 1). With
--feedback tracker every frame (5 Hz by default) is simulated from the true attitude and rate
(with smear), its stars detected and followed by startrack's Tracker; the attitude and rate
reach the controller after the exposure and the measured processing time, propagated to the
present. Prints the step metrics against the seed's Table 5.3 and writes the figures, run.csv
and summary.json (and, with the tracker, frames.csv and tracker_noise.json, which
--feedback tracker-model --noise-model uses for long runs) into --out."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..adcs import (
    FEEDBACKS,
    FIELDS,
    HORIZONS,
    MAX_LATENCY_S,
    PLANTS,
    CubeSat,
    GuidanceOptions,
    LoopConfig,
    Scenario,
    StarTrackerSetup,
    TrackerNoiseModel,
    run_loop,
    run_metrics,
    save_run_plots,
    summary,
    table,
    write_files,
)
from ..errors import InvalidInputError
from ..io import read_json_file
from ._common import check_output_folder, exit_status_epilog, non_empty, print_json
from ._parser import CommandParser
from ._progress import ProgressBar, ensure_database_for

EPILOG = """\
output
  a line with the settings and the wall time, a table per step and overall (steady-state error
  deg over each step's last 20 s, overshoot %, 10-90 % rise time s, 5 % settling time s, average
  and peak coil power W) with the seed's bounds, the star tracker's frames and latency, and the
  files written. With --json one object with the keys feedback, law, plant, duration_s,
  wall_time_s, overall and steps (a list), each holding steady_state_error_deg, overshoot_pct,
  rise_time_s, settling_time_s, avg_power_w, peak_power_w (null where not reached), plus
  meets_table_5_3, seed, plans, tracker (with the star tracker) and files.

""" + exit_status_epilog("0 the run meets the seed's Table 5.3 (steady-state < 4.5 deg, overshoot < 20 %, rise < 8 s, "
                         "settling < 30 s); 1 it does not (the table says where; a run shorter than one step's 20 s "
                         "steady-state window never does); 2 misuse, with one line 'startrack adcs-demo: error: ...' "
                         "on standard error;")


def _parser() -> argparse.ArgumentParser:
    p = CommandParser(prog="startrack adcs-demo", description=__doc__, epilog=EPILOG,
                      formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--feedback", choices=FEEDBACKS, default="tracker", help="feedback source (default tracker)")
    p.add_argument("--duration-s", type=float, default=700.0, help="simulated time, s (default 700)")
    p.add_argument("--out", default="startrack-adcs", type=non_empty, help="output folder (default startrack-adcs)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--law", choices=("lqr", "pd"), default="lqr", help="tracking law (default lqr; pd: baseline)")
    p.add_argument("--horizon", choices=HORIZONS, default="shrinking", help="replanning horizon (default shrinking)")
    p.add_argument("--plant", choices=PLANTS, default="single-axis", help="plant (default single-axis)")
    p.add_argument("--field", choices=FIELDS, default="helmholtz",
                   help="three-axis plant: Helmholtz field or the dipole along a 500 km orbit")
    p.add_argument("--j22-kg-m2", type=float, default=CubeSat().j22,
                   help="moment of inertia about y, kg m^2 (default 1.05e-3; the seed prints 1.05e-2)")
    p.add_argument("--frame-rate-hz", type=float, default=5.0, help="star tracker frames per second (default 5)")
    p.add_argument("--latency-s", type=float, default=None,
                   help="fixed processing latency per frame, s (default: the measured time of each frame)")
    p.add_argument("--noise-model", help="tracker_noise.json of a tracker run (needed by --feedback tracker-model)")
    p.add_argument("--seed", type=int, default=0, help="seed of the IMU, PWM and image noise (default 0)")
    return p


def _config(args: argparse.Namespace) -> LoopConfig:
    if args.feedback == "tracker-model" and not args.noise_model:
        raise InvalidInputError("--feedback tracker-model needs --noise-model FILE (the tracker_noise.json "
                                "written by a --feedback tracker run)")
    noise = None
    if args.noise_model:
        noise = TrackerNoiseModel.from_dict(read_json_file(args.noise_model, "tracker noise model"))
    if args.plant == "single-axis" and args.field != "helmholtz":
        raise InvalidInputError("--field dipole needs --plant three-axis")
    if args.latency_s is not None and not 0 <= args.latency_s <= MAX_LATENCY_S:  # before the run, in its words
        raise InvalidInputError(f"--latency-s must be 0 to {MAX_LATENCY_S:g} s, got {args.latency_s:g}")
    tracker = StarTrackerSetup(frame_rate_hz=args.frame_rate_hz, latency_s=args.latency_s, seed=args.seed)
    return LoopConfig(cubesat=CubeSat().with_j22(args.j22_kg_m2), scenario=Scenario(duration_s=args.duration_s),
                      guidance=GuidanceOptions(horizon=args.horizon), feedback=args.feedback, law=args.law,
                      plant=args.plant, b_field=args.field, tracker=tracker, noise_model=noise, seed=args.seed)


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    out = Path(args.out)
    check_output_folder(out)
    config = _config(args)
    if config.feedback == "tracker":
        ensure_database_for(camera=config.tracker.camera)
    record = run_loop(config, progress=ProgressBar("  simulated s"))
    steps, overall = run_metrics(record)
    data = summary(record, steps, overall)
    files = save_run_plots(record, out)
    files += write_files(record, data, out)
    data["files"] = [str(f) for f in files]
    if args.json:
        print_json(data)
    else:
        _print_text(config, data)
    return 0 if data["meets_table_5_3"] else 1


def _ms(seconds: float | None) -> str:
    """A time in ms for the table, or "n/a" when no frame was tracked (the summary holds None)."""
    return "n/a" if seconds is None else f"{1e3 * seconds:.0f} ms"


def _print_text(config: LoopConfig, data: dict) -> None:
    sat = config.cubesat
    print(f"{data['feedback']} feedback, {data['law'].upper()} law, {data['plant']} plant, J22 {sat.j22:.3g} kg m^2: "
          f"{data['duration_s']:g} s simulated in {data['wall_time_s']:.1f} s wall time\n")
    print(table(data))
    tr = data.get("tracker")
    if tr:
        print(f"\ntracker     {tr['tracked']} of {tr['frames']} frames tracked; latency median "
              f"{_ms(tr['latency_median_s'])} (95 % {_ms(tr['latency_p95_s'])}), processing "
              f"{_ms(tr['processing_median_s'])}; y-angle error {tr.get('theta_error_rms_arcsec', 0):.1f} "
              f"arcsec rms, rate {tr.get('rate_error_sigma_arcsec_s', 0):.1f} arcsec/s")
    verdict = "meets" if data["meets_table_5_3"] else "does not meet"
    print(f"\n{verdict} the seed's Table 5.3; files: {', '.join(data['files'])}")

