"""Rigs of 1, 2 and 3 camera heads: the joint star-level solution against one head's, against
fusing the heads' own quaternions, split-FOV classification against PSF elongation, and time.

    python benchmarks/rig_benchmark.py [--attitudes 1000] [--sparse 1000] [--frames 10] [--seed 1]
                                       [--clock wall|cpu]

Heads: 1024 x 1024 px, 15 deg (53 arcsec per pixel); head a along body +z, b turned 90 deg about
body x, c 90 deg about body y. Star lists (:func:`startrack.simulate._rig.rig_star_lists`): catalog
stars to V 6, 0.2 px centroid noise, the 40 brightest per head. Errors are the rotation vector of
``truth * estimate^-1`` in the body frame, which is head a's camera frame: "cross" is across head
a's boresight, "roll" about it. Printed:

1. Over ``--attitudes`` seeded random attitudes per rig: success (within 5 pixel angles at the
   image corner, :mod:`startrack.analysis._scoring`'s judgement), rms cross and roll error of the
   joint solution, of head a alone (``solve_stars`` on its list), and of every head solved alone
   with its quaternion fused with the others' (covariance-weighted; what rigs that fuse per-head
   quaternions do), and the roll ratio against head a alone. Rms over the correct solutions.
2. Sparse fields (``--sparse`` attitudes, at most 3 stars per head): success of the joint solve
   against head a alone (a lost-in-space matcher needs 4 stars) and quaternion fusion.
3. Median solve time of the joint solve against ``solve_stars`` on head a's list (same lists);
   wall-clock, or with ``--clock cpu`` the CPU time of the calling thread (for a loaded machine).
4. The roll ratio for two heads against their separation.
5. Split-FOV frames (two orthogonal fields, V <= 7.5, the generic-cmos sensor) over ``--frames``
   random attitudes per elongation: misclassified and ambiguous spots with intensity-weighted
   moments and with Samaan 2002 eq. 4's unweighted mask sums.
6. Two heads with head b's mounting off by a known angle, about b's boresight (the axis a single
   head knows worst) or across it: how often the rig flags b inconsistent, the median consistency
   angle and the rms error of the joint solution.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera, CameraRig, RigHead, solve_rig, solve_stars
from startrack.analysis._scoring import roll_weight, tolerance_rad
from startrack.attitude import covariance_to_body
from startrack.detect import StarDetector
from startrack.frames import random_rotations
from startrack.multihead._split_fov import classify_fields, moments_radius_px, spot_moments
from startrack.rig import PsfShape
from startrack.simulate import get_sensor_preset
from startrack.simulate._rig import rig_star_lists
from startrack.simulate._split_fov import simulate_split_frame
from startrack.units import ARCSEC

CAMERA = Camera.from_fov(1024, 1024, 15.0)
MOUNTS = {"a": Rotation.identity(), "b": Rotation.from_euler("x", 90, degrees=True),
          "c": Rotation.from_euler("y", 90, degrees=True)}
SIGMA_PX = 0.2
ELONGATIONS = (1.0, 1.1, 1.25, 1.5, 2.0, 3.0)
CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}


def rig_of(n: int, separation_deg: float = 90.0) -> CameraRig:
    mounts = [MOUNTS["a"], Rotation.from_euler("x", separation_deg, degrees=True),
              Rotation.from_euler("y", separation_deg, degrees=True)]
    return CameraRig([RigHead(name, CAMERA, mounts[k]) for k, name in enumerate("abc"[:n])])


def fused_quaternions(alone: dict, rig) -> Rotation | None:
    """The heads' lost-in-space solutions, each alone, in the body frame fused with their covariances
    (information-weighted mean of the small rotations from the first one): quaternion-level fusion."""
    parts = [(h.rot_cam_from_body.inv() * alone[h.name].rot_cam_from_icrs,
              covariance_to_body(alone[h.name].covariance_rad2, h.rot_cam_from_body))
             for h in rig if alone[h.name].solved]
    if not parts:
        return None
    base = parts[0][0]
    info = sum(np.linalg.inv(c) for _, c in parts)
    rhs = sum(np.linalg.inv(c) @ (r * base.inv()).as_rotvec() for r, c in parts)
    return Rotation.from_rotvec(np.linalg.solve(info, rhs)) * base


def errors(truth: Rotation, estimate: Rotation | None) -> tuple[float, float, bool]:
    """(cross, roll) error in arcsec about head a's boresight, and whether it is correct."""
    if estimate is None:
        return math.nan, math.nan, False
    ex, ey, ez = (truth * estimate.inv()).as_rotvec()
    correct = math.sqrt(ex * ex + ey * ey + (roll_weight(CAMERA) * ez) ** 2) <= tolerance_rad(CAMERA)
    return math.hypot(ex, ey) / ARCSEC, abs(ez) / ARCSEC, correct


def rms(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v * v))) if v.size else math.nan


def accuracy(n_heads: int, attitudes: int, seed: int, max_stars: int = 40, separation_deg: float = 90.0) -> dict:
    """Joint, head-a-alone and fused-quaternion errors and success over seeded attitudes."""
    rig, rng = rig_of(n_heads, separation_deg), np.random.default_rng(seed)
    rows = {"joint": [], "single": [], "fused": []}
    for _ in range(attitudes):
        truth = random_rotations(None, rng)
        lists = rig_star_lists(rig, truth, max_mag=6.0, rng=rng, sigma_px=SIGMA_PX, max_stars=max_stars)
        sol = solve_rig({n: s.stars for n, s in lists.items()}, rig)
        alone = {h.name: solve_stars(*lists[h.name].stars[:2], camera=h.camera) for h in rig}
        rows["joint"].append(errors(truth, sol.rot_body_from_icrs if sol.solved else None))
        rows["single"].append(errors(truth, alone["a"].rot_cam_from_icrs if alone["a"].solved else None))
        rows["fused"].append(errors(truth, fused_quaternions(alone, rig)))
    return {k: np.array(v, dtype=float) for k, v in rows.items()}


def print_accuracy(args) -> None:
    print(f"1. Accuracy over {args.attitudes} seeded attitudes (15 deg heads, V <= 6, {SIGMA_PX} px, 40 stars/head)")
    print(f"{'heads':>5} {'method':<18} {'success':>8} {'cross rms':>10} {'roll rms':>9} {'roll ratio':>11}")
    for n in (1, 2, 3):
        res = accuracy(n, args.attitudes, args.seed + n)
        single_roll = rms(res["single"][:, 1])
        for name, label in (("joint", "joint (stars)"), ("single", "head a alone"), ("fused", "fused quaternions")):
            r = res[name]
            ok = r[:, 2] > 0
            print(f"{n:>5} {label:<18} {np.mean(ok):>8.4f} {rms(r[ok, 0]):>9.2f}\" {rms(r[ok, 1]):>8.2f}\" "
                  f"{rms(r[ok, 1]) / single_roll:>11.3f}")
    print()


def print_sparse(args) -> None:
    print(f"2. Sparse fields: at most 3 stars per head, {args.sparse} seeded attitudes")
    print(f"{'heads':>5} {'joint':>8} {'head a alone':>13} {'fused quaternions':>18}")
    for n in (1, 2, 3):
        res = accuracy(n, args.sparse, args.seed + 10 + n, max_stars=3)
        print(f"{n:>5} {np.mean(res['joint'][:, 2] > 0):>8.4f} {np.mean(res['single'][:, 2] > 0):>13.4f} "
              f"{np.mean(res['fused'][:, 2] > 0):>18.4f}")
    print()


def print_timing(args) -> None:
    n_lists = min(args.attitudes, 300)
    clock = CLOCKS[args.clock]
    print(f"3. Solve time, median over {n_lists} attitudes (warm; {args.clock} clock, load {os.getloadavg()[0]:.2f})")
    print(f"{'heads':>5} {'joint solve_rig':>16} {'solve_stars head a':>19} {'ratio':>6}")
    for n in (1, 2, 3):
        rig, rng = rig_of(n), np.random.default_rng(args.seed + 20 + n)
        solve_rig({n_: s.stars for n_, s in rig_star_lists(rig, random_rotations(None, 0), rng=rng).items()}, rig)
        joint, single = [], []
        for _ in range(n_lists):
            lists = rig_star_lists(rig, random_rotations(None, rng), max_mag=6.0, rng=rng, sigma_px=SIGMA_PX)
            t0 = clock()
            solve_rig({n_: s.stars for n_, s in lists.items()}, rig)
            t1 = clock()
            solve_stars(*lists["a"].stars[:2], camera=CAMERA)
            joint.append(t1 - t0)
            single.append(clock() - t1)
        print(f"{n:>5} {np.median(joint) * 1e3:>13.2f} ms {np.median(single) * 1e3:>16.2f} ms "
              f"{np.median(joint) / np.median(single):>6.2f}")
    print()


def print_separation(args) -> None:
    n = min(args.attitudes, 300)
    print(f"4. Two heads: joint roll rms / head a's against their separation ({n} attitudes each)")
    print(f"{'separation':>10} {'joint roll':>11} {'head a roll':>12} {'ratio':>6}")
    for sep in (10.0, 30.0, 60.0, 90.0):
        res = accuracy(2, n, args.seed + 30, separation_deg=sep)
        j, s = rms(res["joint"][:, 1]), rms(res["single"][:, 1])
        print(f"{sep:>8.0f} d {j:>10.2f}\" {s:>11.2f}\" {j / s:>6.3f}")
    print()


def split_rig(elongation: float) -> CameraRig:
    return CameraRig([
        RigHead("left", CAMERA, MOUNTS["a"], detector="split", psf=PsfShape(elongation, 1.0, 90.0)),
        RigHead("right", CAMERA, MOUNTS["b"], detector="split", psf=PsfShape(elongation, 1.0, 0.0))])


def classification(elongation: float, frames: int, seed: int) -> dict[str, tuple[int, int, int]]:
    """(misclassified, ambiguous, spots) per weighting over simulated split frames."""
    rig, rng, sensor = split_rig(elongation), np.random.default_rng(seed), get_sensor_preset("generic-cmos")
    out = {"intensity": [0, 0, 0], "mask": [0, 0, 0]}
    for _ in range(frames):
        frame = simulate_split_frame(rig, "split", random_rotations(None, rng), max_mag=7.5, sensor=sensor, rng=rng,
                                     epoch_jyear=2000.0)
        found = StarDetector().detect(frame.image)
        t = frame.truth
        d2 = (found.x[:, None] - t.x[None]) ** 2 + (found.y[:, None] - t.y[None]) ** 2
        nearest = np.argmin(d2, axis=1)
        real = d2[np.arange(len(nearest)), nearest] < 1.5**2
        field = np.array([rig.names.index(f) for f in t.field[nearest]])
        for weighting, counts in out.items():
            m = spot_moments(frame.image, found.x, found.y, background=found.background, noise=found.noise,
                             radius_px=moments_radius_px(rig.heads), weighting=weighting)
            c = classify_fields(m, rig.heads)
            counts[0] += int(np.sum(real & ~c.ambiguous & (c.field != field)))
            counts[1] += int(np.sum(real & c.ambiguous))
            counts[2] += int(np.sum(real))
    return {k: tuple(v) for k, v in out.items()}


def print_split(args) -> None:
    print(f"5. Split-FOV field classification, {args.frames} frames per elongation (minor sigma 1 px, V <= 7.5)")
    print(f"{'elongation':>10} {'spots':>6} | {'intensity: wrong':>16} {'ambiguous':>9} | "
          f"{'eq. 4 mask: wrong':>17} {'ambiguous':>9}")
    for elongation in ELONGATIONS:
        res = classification(elongation, args.frames, args.seed + 40)
        wi, ai, n = res["intensity"]
        wm, am, _ = res["mask"]
        print(f"{elongation:>10.2f} {n:>6} | {100 * wi / n:>15.2f}% {100 * ai / n:>8.2f}% | "
              f"{100 * wm / n:>16.2f}% {100 * am / n:>8.2f}%")
    print()


def print_mounting(args) -> None:
    n = min(args.attitudes, 200)
    print(f"6. Wrong mounting of head b, {n} attitudes each")
    print(f"{'axis':>6} {'error':>7} {'flagged':>8} {'median consistency':>19} {'joint err rms':>14}")
    true_rig = rig_of(2)
    for axis, error_deg in [("about", e) for e in (0.0, 0.005, 0.01, 0.02, 0.05, 0.5)] + \
                           [("across", e) for e in (0.002, 0.005, 0.01)]:
        turn = Rotation.from_euler("z" if axis == "about" else "x", error_deg, degrees=True)  # b's camera axes
        wrong = CameraRig([true_rig.head("a"), RigHead("b", CAMERA, turn * MOUNTS["b"])])
        rng = np.random.default_rng(args.seed + 50)
        flagged, consistency, err = 0, [], []
        for _ in range(n):
            truth = random_rotations(None, rng)
            lists = rig_star_lists(true_rig, truth, max_mag=6.0, rng=rng, sigma_px=SIGMA_PX)
            sol = solve_rig({k: s.stars for k, s in lists.items()}, wrong)
            flagged += "b" in sol.inconsistent_heads
            consistency.append(sol.consistency_deg * 3600.0)
            err.append((truth * sol.rot_body_from_icrs.inv()).magnitude() / ARCSEC)
        print(f"{axis:>6} {error_deg * 3600:>6.0f}\" {flagged / n:>8.3f} {np.median(consistency):>18.1f}\" "
              f"{rms(err):>13.2f}\"")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--attitudes", type=int, default=1000)
    parser.add_argument("--sparse", type=int, default=1000)
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="wall")
    args = parser.parse_args()
    t0 = time.perf_counter()
    print_accuracy(args)
    print_sparse(args)
    print_timing(args)
    print_separation(args)
    print_split(args)
    print_mounting(args)
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
