"""Solving real photos and wide or narrow simulated frames from pixels, with no hint.

Part 1, the eight real images of ``../shared/realdata`` (see its README): each is solved by
``startrack.solve_image`` with nothing said about the field of view (the default search, 3 to
100 deg) and, for comparison, with the earlier default range of 5 to 35 deg. Printed per image:
solved or not, the error against astrometry.net's solution (the direction of the image centre
in pixels of its plate scale, and the roll in degrees), the stars detected among astrometry.net's
genuine matches (``detect_realdata.reference``: its ``.corr`` rows, chance coincidences left out)
and among them the ones our solution matched to a catalog star, and the time (detection and
identification, ``solve_time_s``) and, apart, that of the detection alone (a separate run of
the default detector on the same image). Then the same images flipped left to right, as a
star diagonal or a flipped file gives them: they should solve as mirror images (status "ok
mirrored"; the centre is compared, the roll of a mirrored camera is not). Last, the images as
given with ``guided=True`` (the catalog stars the solution predicts measured too,
``startrack.identify._guided``): "detected" then counts the detector's stars and those.

Part 2, simulated frames (``startrack.simulate.simulate_frame``, the generic CMOS sensor, noise
on) of cameras nobody calibrated, at random attitudes, solved by ``solve_image`` with no hint:

============  ===========  =========================  ===========================================
camera        size (px)    lens                       stands for
============  ===========  =========================  ===========================================
3 deg         1024 x 1024  pinhole                    a small telescope, stars to V 10
50 deg        1640 x 1232  k1 -0.03 (2 % at corner)   a Raspberry Pi camera module, stars to V 6.5
70 deg        1920 x 1080  k1 -0.06, k2 +0.01 (5 %)   a webcam, stars to V 6.5
90 deg        1600 x 1200  k1 -0.05 (7 % at corner)   a wide lens, stars to V 6
============  ===========  =========================  ===========================================

(The lens coefficients are plausible barrel distortions for such lenses, chosen here; they are not
calibrations of particular lenses.) Printed per camera: solved within 2 px (the largest
displacement of the image centre and corners between the true and solved attitudes, through the
true camera), solved farther off (false), not solved, the median and 95th-percentile time of
detection and identification, and the median of identification alone (that time less the
detector's on the same frame, timed apart). With ``--wide``, the same for ultra-wide frames
beyond the default search (:data:`WIDE_CAMERAS`: 110, 120, 135 and 150 deg, 1800 x 1200 px,
k1 = -0.005), solved with their field of view given, with 90-150 deg searched, and with no hint
(``solve_image`` then searches 90-150 deg after the default search finds nothing).

Part 3 (``--lens-term``), the lens term of the pattern tolerance measured: star lists (the 60
brightest catalog stars to V 7.5 through the lens, 0.3 px centroid noise, 0.2 mag of magnitude
noise, 4 false stars among the first 14) of 1600 x 1200 cameras at 50, 70 and 90 deg with k1 of
-0.1, -0.05, +0.05 and +0.1, solved with no hint, with the lens term off
(``MatcherOptions(max_distortion=0)``) and at its default. The 90 deg, k1 = -0.1 lens folds back
at 61 deg off axis, before its corners (:func:`fold_tan`): its lists hold only the stars inside
that angle (the polynomial would put the ~1,400 catalog stars between 61 and 78 deg back into
the frame, where no lens puts them), and its error is measured at the corners pulled in to where
the lens is one to one (:func:`error_points`; at the corners themselves the true lens maps to no
direction, and every solve of it counted as false, 2 px off or not: they were 0.05-0.16 px off).

Usage::

    .venv/bin/python benchmarks/realdata_benchmark.py [--frames 20] [--seed 1] [--no-real] [--no-sim]
                                                      [--wide] [--lens-term] [--lists 30]
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_realdata import REALDATA, reference, score  # noqa: E402

from startrack import Camera, solve_image  # noqa: E402
from startrack.camera import radial_fold_r2  # noqa: E402
from startrack.detect import StarDetector  # noqa: E402
from startrack.frames import angle_between, radec_to_vector, random_rotations  # noqa: E402
from startrack.identify import MatcherOptions  # noqa: E402
from startrack.io import read_image  # noqa: E402
from startrack.simulate import get_sensor_preset, simulate_frame  # noqa: E402
from startrack.units import ARCSEC, DEG  # noqa: E402


@dataclass(frozen=True)
class SimCamera:
    """A simulated camera of part 2: name, size, horizontal FOV, lens and magnitude limit."""

    name: str
    width: int
    height: int
    fov_deg: float
    k1: float
    k2: float
    max_mag: float

    def camera(self) -> Camera:
        return Camera.from_fov(self.width, self.height, self.fov_deg).with_distortion(k1=self.k1, k2=self.k2)


SIM_CAMERAS = (
    SimCamera("3 deg", 1024, 1024, 3.0, 0.0, 0.0, 10.0),
    SimCamera("50 deg", 1640, 1232, 50.0, -0.03, 0.0, 6.5),
    SimCamera("70 deg", 1920, 1080, 70.0, -0.06, 0.01, 6.5),
    SimCamera("90 deg", 1600, 1200, 90.0, -0.05, 0.0, 6.0),
)

WIDE_CAMERAS = tuple(SimCamera(f"{fov:.0f} deg", 1800, 1200, fov, -0.005, 0.0, 6.0)
                     for fov in (110.0, 120.0, 135.0, 150.0))
"""``--wide``: ultra-wide rectilinear lenses (a 12-14 mm lens on a full-frame camera, a phone's
ultra-wide) with a mild barrel (k1 = -0.005, 2-4 % at the corners), beyond the default search."""


# --- part 1: the real images ------------------------------------------------------------------
def _truth_rows() -> list[dict[str, str]]:
    with open(REALDATA / "truth.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def real_row(row: dict[str, str], fov_range_deg: tuple[float, float] | None, flip: bool = False,
             guided: bool = False) -> dict:
    """Solve one real image (no hint, or the given range) and compare with astrometry.net; with
    ``flip``, the image flipped left to right (a mirror image of the sky: its roll is not
    compared, its solution should say ``mirrored``); with ``guided``, the solve measures the
    catalog stars it predicts too (``solve_image(guided=True)``): "detected" then counts the
    detector's and those stars together."""
    image = read_image(REALDATA / row["set"] / row["file"])
    ref = reference(row["file"])
    if flip:
        width = image.data.shape[1]
        image = replace(image, data=np.ascontiguousarray(image.data[:, ::-1]))
        ref = replace(ref, x=(width - 1) - ref.x, hip_x=(width - 1) - ref.hip_x)
    detect_s = _detect_s(image.data)
    solution = solve_image(image, fov_range_deg=fov_range_deg, guided=guided)
    found = solution.detections
    out = {"file": row["file"], "solved": solution.solved, "status": solution.status.value,
           "mirrored": bool(solution.solved and solution.camera.mirrored),
           "time_ms": solution.solve_time_s * 1e3, "detect_ms": detect_s * 1e3, "an_matched": int(ref.x.size),
           "detected": score(found.x, found.y, ref).found, "identified": 0,
           "centre_err_px": float("nan"), "roll_err_deg": float("nan"), "fov_deg": float("nan")}
    if not solution.solved:
        return out
    matched = solution.matches.det_index
    roll_err = float("nan") if flip else (solution.roll_deg - float(row["roll_tetra3_deg"]) + 180.0) % 360.0 - 180.0
    out.update(centre_err_px=centre_error_px(solution, row), roll_err_deg=roll_err,
               fov_deg=solution.fov_deg, identified=score(found.x[matched], found.y[matched], ref).found)
    return out


def centre_error_px(solution, row: dict[str, str]) -> float:
    """Angle between a solved image's centre ((W - 1) / 2, (H - 1) / 2) and astrometry.net's
    (``truth.csv`` row ``row``), in the image's pixels (its ``pixscale_arcsec``)."""
    width, height = int(row["width"]), int(row["height"])
    centre = solution.rot_cam_from_icrs.inv().apply(solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2))
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    return float(angle_between(centre, truth) / (float(row["pixscale_arcsec"]) * ARCSEC))


def _detect_s(data: np.ndarray) -> float:
    """Seconds the default detector takes on an image (one run)."""
    t0 = time.perf_counter()
    StarDetector().detect(data)
    return time.perf_counter() - t0


def print_real(rows: list[dict], label: str, flipped: bool = False) -> None:
    print(f"\nReal images, {label}")
    print(f"{'image':<16} {'status':<14} {'centre px':>9} {'roll deg':>8} {'FOV deg':>8} "
          f"{'a.net stars':>11} {'detected':>8} {'identified':>10} {'time ms':>8} {'detect ms':>9}")
    for r in rows:
        status = r["status"] + (" mirrored" if r["mirrored"] else "")
        print(f"{r['file']:<16} {status:<14} {r['centre_err_px']:>9.2f} {r['roll_err_deg']:>8.3f} "
              f"{r['fov_deg']:>8.3f} {r['an_matched']:>11d} {r['detected']:>8d} {r['identified']:>10d} "
              f"{r['time_ms']:>8.1f} {r['detect_ms']:>9.1f}")
    solved = [r for r in rows if r["solved"]]
    within = sum(r["centre_err_px"] < 2.0 and (flipped or abs(r["roll_err_deg"]) < 0.2) for r in solved)
    limits = "2 px" if flipped else "2 px and 0.2 deg"
    print(f"solved {len(solved)} of {len(rows)} ({sum(r['mirrored'] for r in solved)} as mirror images), {within} "
          f"within {limits} of astrometry.net; median time {np.median([r['time_ms'] for r in rows]):.1f} ms")


# --- part 2: simulated frames -----------------------------------------------------------------
def fold_tan(camera: Camera) -> float:
    """tan of the off-axis angle where the camera's radial distortion stops growing with it (the
    smallest r = |(v_x, v_y)| / v_z with d(r (1 + k1 r^2 + k2 r^4 + k3 r^6)) / dr = 0), inf when it
    never does (:func:`startrack.camera.radial_fold_r2`). Beyond it the polynomial folds back:
    ``Camera.vector_to_pixel`` gives NaN there, and image points past its largest distorted
    radius map to no direction."""
    return math.sqrt(radial_fold_r2(camera.k1, camera.k2, camera.k3))


def error_points(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The image centre and corners (pixels), each corner pulled in along its diagonal to just
    inside the largest radius the lens maps one to one (the 90 deg, k1 = -0.1 lens of part 3
    folds at 61 deg off axis, before its corners)."""
    x = np.array([camera.cx, 0.0, camera.width - 1.0, 0.0, camera.width - 1.0])
    y = np.array([camera.cy, 0.0, 0.0, camera.height - 1.0, camera.height - 1.0])
    r = fold_tan(camera)
    if np.isfinite(r):
        largest = 0.999 * r * (1.0 + r * r * (camera.k1 + r * r * (camera.k2 + r * r * camera.k3)))
        a, b = (x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy
        shrink = np.minimum(1.0, largest / np.maximum(np.hypot(a, b), 1e-12))
        x, y = camera.cx + (x - camera.cx) * shrink, camera.cy + (y - camera.cy) * shrink
    return x, y


def error_px(truth, solution, camera: Camera) -> float:
    """Largest displacement (pixels, through the true camera) of the image centre and corners
    (:func:`error_points`) between the true and the solved attitude."""
    x, y = error_points(camera)
    sky = truth.inv().apply(camera.pixel_to_vector(x, y))
    px, py = camera.vector_to_pixel(solution.rot_cam_from_icrs.apply(sky))
    return float(np.max(np.hypot(px - x, py - y)))


def sim_camera_run(spec: SimCamera, frames: int, seed: int, hint: dict | None = None) -> dict:
    """Render and solve ``frames`` frames of one simulated camera, with the ``solve_image`` keyword
    arguments ``hint`` (none: the default search)."""
    camera, sensor = spec.camera(), get_sensor_preset("generic-cmos")
    rng = np.random.default_rng([seed, int(spec.fov_deg)])
    ok = false = 0
    times, identify, errors = [], [], []
    for truth in random_rotations(frames, rng=rng):
        sim = simulate_frame(camera, truth, max_mag=spec.max_mag, sensor=sensor, epoch_jyear=2000.0, rng=rng)
        detect_s = _detect_s(sim.image)
        solution = solve_image(sim.image, **(hint or {}))
        times.append(solution.solve_time_s)
        identify.append(solution.solve_time_s - detect_s)
        if solution.solved:
            err = error_px(truth, solution, camera)
            errors.append(err)
            ok, false = ok + (err < 2.0), false + (err >= 2.0)
    return {"camera": spec.name, "frames": frames, "ok": ok, "false": false, "unsolved": frames - ok - false,
            "median_err_px": float(np.median(errors)) if errors else float("nan"),
            "median_ms": float(np.median(times)) * 1e3, "p95_ms": float(np.percentile(times, 95)) * 1e3,
            "identify_median_ms": float(np.median(identify)) * 1e3}


def print_sim(rows: list[dict], label: str = "no hint (default search 3-100 deg)") -> None:
    print(f"\nSimulated frames, {label}, lens not calibrated")
    print(f"{'camera':<8} {'frames':>6} {'within 2 px':>11} {'false':>5} {'unsolved':>8} {'median err px':>13} "
          f"{'median ms':>9} {'p95 ms':>8} {'identify ms':>11}")
    for r in rows:
        print(f"{r['camera']:<8} {r['frames']:>6d} {r['ok']:>11d} {r['false']:>5d} {r['unsolved']:>8d} "
              f"{r['median_err_px']:>13.3f} {r['median_ms']:>9.1f} {r['p95_ms']:>8.1f} "
              f"{r['identify_median_ms']:>11.1f}")


def print_wide(frames: int, seed: int) -> None:
    """``--wide``: the frames of :data:`WIDE_CAMERAS`, their field of view given, searched over
    90-150 deg, and with no hint."""
    print_sim([sim_camera_run(spec, frames, seed, {"fov_deg": spec.fov_deg}) for spec in WIDE_CAMERAS],
              "ultra-wide, the field of view given")
    print_sim([sim_camera_run(spec, frames, seed, {"fov_range_deg": (90.0, 150.0)}) for spec in WIDE_CAMERAS],
              "ultra-wide, 90-150 deg searched")
    print_sim([sim_camera_run(spec, frames, seed) for spec in WIDE_CAMERAS],
              "ultra-wide, no hint (the default search, then 90-150 deg)")


# --- part 3: the lens term, on star lists ----------------------------------------------------
def lens_list(camera: Camera, truth, rng: np.random.Generator, vectors: np.ndarray, mag: np.ndarray):
    """Part 3's star list of one attitude: (x, y), brightest first, 4 false stars among the first 14.
    Only stars inside the lens's one-to-one range (:func:`fold_tan`) are seen: the polynomial of
    a strong barrel folds the directions beyond it back into the frame, where no lens puts them."""
    v = vectors @ truth.as_matrix().T
    front = (v[:, 2] > 0.2) & (np.hypot(v[:, 0], v[:, 1]) < fold_tan(camera) * v[:, 2])
    x, y = camera.vector_to_pixel(v[front])
    inside = camera.in_image(x, y, margin_px=1.0)
    order = np.argsort(mag[front][inside] + rng.normal(0.0, 0.2, inside.sum()))[:60]
    x, y = x[inside][order] + rng.normal(0, 0.3, order.size), y[inside][order] + rng.normal(0, 0.3, order.size)
    fx, fy = rng.uniform(0, camera.width - 1, 4), rng.uniform(0, camera.height - 1, 4)
    x, y = np.concatenate([x[:10], fx, x[10:]]), np.concatenate([y[:10], fy, y[10:]])
    return np.clip(x, 0, camera.width - 1), np.clip(y, 0, camera.height - 1)


def _lens_case(camera: Camera, lists: list, options: MatcherOptions | None) -> dict:
    """Solve part 3's lists of one lens with these options: within 2 px, false, CPU times."""
    from startrack.solve import solve_stars

    ok = false = 0
    times = []
    for truth, (x, y) in lists:
        t0 = time.thread_time()
        solution = solve_stars(x, y, width=camera.width, height=camera.height, options=options)
        times.append(time.thread_time() - t0)
        if solution.solved:
            good = error_px(truth, solution, camera) < 2.0
            ok, false = ok + good, false + (not good)
    return {"ok": ok, "false": false, "n": len(lists), "median_ms": float(np.median(times)) * 1e3,
            "p95_ms": float(np.percentile(times, 95)) * 1e3}


def lens_term_rows(n_lists: int, seed: int) -> list[dict]:
    """Part 3: every lens, with the lens term off and at its default."""
    from startrack.catalog import load_catalog

    stars = load_catalog().brighter_than(7.5)
    vectors, mag = stars.vectors(2000.0), stars.v_mag
    rows = []
    for fov in (50.0, 70.0, 90.0):
        for k1 in (-0.1, -0.05, 0.05, 0.1):
            camera = Camera.from_fov(1600, 1200, fov).with_distortion(k1=k1)
            rng = np.random.default_rng([seed, int(fov), int(round(k1 * 100)) + 50])
            lists = [(t, lens_list(camera, t, rng, vectors, mag)) for t in random_rotations(n_lists, rng=rng)]
            for label, options in (("off", MatcherOptions(max_distortion=0.0)), ("default", None)):
                rows.append({"fov": fov, "k1": k1, "term": label, **_lens_case(camera, lists, options)})
    return rows


def print_lens_term(rows: list[dict]) -> None:
    default = MatcherOptions().max_distortion
    print(f"\nLens term of the look-up tolerance: off, or |k1| <= {default:g} (default); star lists, no hint; "
          "CPU time of the solving thread")
    print(f"{'FOV':>5} {'k1':>6} {'term':<8} {'within 2 px':>11} {'false':>5} {'median ms':>9} {'p95 ms':>8}")
    for r in rows:
        print(f"{r['fov']:>5.0f} {r['k1']:>+6.2f} {r['term']:<8} {r['ok']:>8d}/{r['n']:<2d} {r['false']:>5d} "
              f"{r['median_ms']:>9.1f} {r['p95_ms']:>8.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20, help="simulated frames per camera (default 20)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-real", action="store_true", help="skip the real images")
    parser.add_argument("--no-sim", action="store_true", help="skip the simulated frames")
    parser.add_argument("--lens-term", action="store_true", help="also measure the lens term on star lists")
    parser.add_argument("--wide", action="store_true", help="also solve ultra-wide frames (110-150 deg), their "
                        "field of view given or a range of 90-150 deg searched")
    parser.add_argument("--lists", type=int, default=30, help="star lists per lens of --lens-term (default 30)")
    args = parser.parse_args(argv)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    solve_image(np.zeros((64, 64)))  # load the database and the compiled search before timing
    if not args.no_real:
        if not (REALDATA / "truth.csv").is_file():
            print(f"real images: {REALDATA} is absent, skipped")
        else:
            rows = _truth_rows()
            print_real([real_row(r, None) for r in rows], "no hint (default search 3-100 deg)")
            print_real([real_row(r, (5.0, 35.0)) for r in rows], "FOV range 5-35 deg (the earlier default)")
            print_real([real_row(r, None, flip=True) for r in rows],
                       "flipped left to right (mirror images), no hint", flipped=True)
            print_real([real_row(r, None, guided=True) for r in rows],
                       "no hint, with the stars the solution predicts measured (guided=True)")
    if not args.no_sim:
        print_sim([sim_camera_run(spec, args.frames, args.seed) for spec in SIM_CAMERAS])
    if args.wide:
        print_wide(args.frames, args.seed)
    if args.lens_term:
        print_lens_term(lens_term_rows(args.lists, args.seed))
    print(f"\nwall {time.perf_counter() - t0:.0f} s; load average {load:.2f} before, {os.getloadavg()[0]:.2f} after "
          f"on {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
