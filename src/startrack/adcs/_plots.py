"""Figures of a closed-loop run (matplotlib's object API: no pyplot, no backend switched).

* ``attitude.png``: the angle about y (truth, estimate, plan, target) and the pointing error
  (true and estimated, against the target) with the seed's 4.5 deg steady-state band;
* ``actuation.png``: commanded and delivered current with the saturation limit, the coil torque
  about y and the power I^2 R;
* ``feedback.png``: the feedback's validity and latency (per frame for the star tracker, the
  estimate's age for the others) and the rate estimate against the truth.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..plotting import new_figure
from ._loop import RunRecord
from ._metrics import SEED_TABLE_5_3

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DPI = 110


def save_run_plots(record: RunRecord, out_dir: str | os.PathLike) -> list[Path]:
    """Write the three figures of ``record`` into ``out_dir`` (created); returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, draw in (("attitude.png", draw_attitude), ("actuation.png", draw_actuation),
                       ("feedback.png", draw_feedback)):
        fig = draw(record)
        fig.savefig(out / name, dpi=DPI)
        written.append(out / name)
    return written


def _title(record: RunRecord) -> str:
    c = record.config
    return f"{c.feedback} feedback, {c.law.upper()} law, {c.plant} plant"


def draw_attitude(record: RunRecord) -> Figure:
    """Angle about y (truth, estimate, plan, target) and the pointing error with the 4.5 deg band."""
    fig = new_figure(figsize=(10, 6.5), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    t, deg = record.t_s, np.degrees
    top.plot(t, deg(record.target_theta), color="0.6", lw=1, ls="--", label="target")
    top.plot(t, deg(record.plan_theta), color="tab:orange", lw=1, label="plan")
    top.plot(t, deg(record.theta_true), color="tab:blue", lw=1.2, label="truth")
    top.plot(t, deg(record.theta_est), color="tab:green", lw=0.6, alpha=0.7, label="estimate")
    top.set_ylabel("angle about y (deg)")
    top.legend(loc="upper left", ncol=4, fontsize=8)
    top.set_title(_title(record))
    band = SEED_TABLE_5_3["steady_state_error_deg"]
    bottom.axhspan(-band, band, color="tab:green", alpha=0.08, label=f"seed requirement +-{band:g} deg")
    bottom.plot(t, deg(record.theta_est - record.target_theta), color="tab:green", lw=0.6, alpha=0.7,
                label="estimated")
    bottom.plot(t, deg(record.theta_true - record.target_theta), color="tab:blue", lw=1, label="true")
    bottom.set_yscale("symlog", linthresh=0.01)
    bottom.set_ylabel("pointing error (deg, symlog)")
    bottom.set_xlabel("time (s)")
    bottom.legend(loc="lower right", fontsize=8)
    return fig


def draw_actuation(record: RunRecord) -> Figure:
    """Commanded and delivered current with the limit, torque about y and power I^2 R."""
    fig = new_figure(figsize=(10, 7.5), layout="constrained")
    cur, tor, pw = fig.subplots(3, 1, sharex=True)
    t, limit = record.t_s, record.config.cubesat.max_current_a
    cur.plot(t, 1e3 * record.current_cmd, color="tab:orange", lw=0.8, label="commanded")
    cur.plot(t, 1e3 * record.current_delivered, color="tab:blue", lw=0.4, alpha=0.7, label="delivered")
    for sign in (-1, 1):
        cur.axhline(1e3 * sign * limit, color="tab:red", lw=0.8, ls="--", label="saturation" if sign > 0 else None)
    saturated = np.abs(record.current_cmd) >= limit * (1 - 1e-9)
    cur.set_ylabel("coil current (mA)")
    cur.legend(loc="upper right", ncol=3, fontsize=8)
    cur.set_title(f"{_title(record)}: saturated {100 * saturated.mean():.1f} % of ticks")
    tor.plot(t, 1e6 * record.torque_y, color="tab:purple", lw=0.5)
    tor.set_ylabel("torque about y (uN m)")
    pw.plot(t, record.power_w, color="tab:brown", lw=0.5)
    pw.axhline(float(np.mean(record.power_w)), color="k", lw=0.8, ls=":",
               label=f"average {np.mean(record.power_w):.4f} W")
    pw.set_ylabel("power I^2 R (W)")
    pw.set_xlabel("time (s)")
    pw.legend(loc="upper right", fontsize=8)
    return fig


def draw_feedback(record: RunRecord) -> Figure:
    """Validity and latency of the feedback, and the rate estimate against the truth."""
    fig = new_figure(figsize=(10, 7.5), layout="constrained")
    valid, rate, rate_err = fig.subplots(3, 1, sharex=True)
    _validity(valid, record)
    t = record.t_s
    rate.plot(t, np.degrees(record.omega_true), color="tab:blue", lw=1.2, label="truth")
    rate.plot(t, np.degrees(record.omega_est), color="tab:green", lw=0.6, alpha=0.8, label="estimate (propagated)")
    if record.frames:
        ok = [f for f in record.frames if f.ok]
        rate.plot([f.t_rate_s for f in ok], np.degrees([f.omega_est_rad_s for f in ok]), ".", ms=1.5,
                  color="tab:red", label="tracker rate (at its time tag)")
    rate.set_ylabel("rate about y (deg/s)")
    rate.legend(loc="upper right", fontsize=8)
    rate_err.plot(t, 3600 * np.degrees(record.omega_est - record.omega_true), color="tab:green", lw=0.5)
    rate_err.set_ylabel("rate error (arcsec/s)")
    rate_err.set_xlabel("time (s)")
    return fig


def _validity(ax, record: RunRecord) -> None:
    """Latency per frame (ms) with invalid frames marked, or the estimate's age without frames."""
    if not record.frames:
        ax.plot(record.t_s, record.est_valid, color="tab:green", lw=1, label="estimate valid")
        ax.set_ylim(-0.1, 1.1)
        ax.set_ylabel("valid (IMU / truth every tick)")
        ax.set_title(_title(record))
        return
    frames = record.frames
    t_mid = np.array([f.t_mid_s for f in frames])
    lat = 1e3 * np.array([f.latency_s for f in frames])
    ok = np.array([f.ok for f in frames])
    ax.plot(t_mid[ok], lat[ok], ".", ms=2, color="tab:green", label="tracked: latency")
    if (~ok).any():
        ax.plot(t_mid[~ok], lat[~ok], "x", ms=4, color="tab:red", label="not tracked")
    ax.set_ylabel("mid-exposure to result (ms)")
    median = float(np.median(lat)) if lat.size else math.nan
    ax.set_title(f"{_title(record)}: {ok.sum()} of {ok.size} frames tracked, median latency {median:.0f} ms")
    ax.legend(loc="upper right", fontsize=8)
