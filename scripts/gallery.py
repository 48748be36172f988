"""The simulator gallery of docs/simulation.md: three frames annotated with their truth.

Regenerate from the repository root with ``.venv/bin/python scripts/gallery.py [--out docs/gallery]``
(needs matplotlib, the ``plot`` extra):

- ``point.png``: a still frame of the Hipparcos sky, true positions circled, the brightest named;
- ``streak.png``: the same camera turning at 1 deg/s during a 0.5 s exposure, each star's start
  (green) and end (red) position from the truth;
- ``satellite.png``: a satellite crossing a field while the camera tracks the stars, with its
  start / end points, magnitude and range, and the Sun / Moon / Earth angles in the title.

Every frame is seeded, so the pictures change only when the simulator does.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from astropy.time import Time

from startrack.analysis._plots import display_stretch
from startrack.camera import Camera
from startrack.frames import rotation_from_radec_roll, vector_to_radec
from startrack.plotting import new_figure
from startrack.simulate import (
    RSO,
    FrameTiming,
    KeplerElements,
    Orbit,
    OrbitalScene,
    SimulatedImage,
    SkyBackground,
    get_sensor_preset,
    simulate_frame,
)
from startrack.simulate._orbits import MU_EARTH_KM3_S2
from startrack.units import DEG

DEFAULT_OUT = Path("docs") / "gallery"
CAMERA = Camera.from_fov(1024, 768, 14.0, name="gallery")
ORION = rotation_from_radec_roll(83.8 * DEG, -1.0 * DEG, 0.0)
EPOCH = Time("2026-09-23T20:00:00", scale="utc")


def _axes(image: np.ndarray, title: str):
    height, width = image.shape
    fig = new_figure(figsize=(9, 9 * height / width + 0.6), dpi=90)
    ax = fig.subplots()
    ax.imshow(display_stretch(image), cmap="gray", origin="upper",
              extent=(-0.5, width - 0.5, height - 0.5, -0.5))
    ax.set_xlim(-0.5, width - 0.5)
    ax.set_ylim(height - 0.5, -0.5)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    return fig, ax


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path)
    return path


def plot_point_frame(sim: SimulatedImage, path: Path, n_labels: int = 12) -> Path:
    """The frame with every true star position circled and the brightest labelled (HIP, V)."""
    t = sim.truth
    inside = t.inside()
    fig, ax = _axes(sim.image, f"still frame: {inside.sum()} stars to V 7.5, {t.exposure_s:g} s "
                               f"(truth: circles; HIP number and V of the {n_labels} brightest)")
    ax.scatter(t.x[inside], t.y[inside], s=110, facecolors="none", edgecolors="tab:cyan", linewidths=0.7)
    for hip, x, y, mag in list(zip(t.ids[inside], t.x[inside], t.y[inside], t.mag[inside], strict=True))[:n_labels]:
        ax.annotate(f"HIP {hip}  V {mag:.1f}", (x, y), xytext=(7, -7), textcoords="offset points",
                    color="tab:cyan", fontsize=7)
    return _save(fig, path)


def plot_streak_frame(sim: SimulatedImage, path: Path) -> Path:
    """The frame with each star's start (green) and end (red) point joined by its chord."""
    t = sim.truth
    lit = t.camera.in_image(t.x_start, t.y_start) | t.camera.in_image(t.x_end, t.y_end)
    rate = np.degrees(t.rate_cam_rad_s)
    fig, ax = _axes(sim.image, f"streaked frame: {t.exposure_s:g} s at ({rate[0]:.2f}, {rate[1]:.2f}, "
                               f"{rate[2]:.2f}) deg/s (camera frame), {t.substeps} sub-steps; "
                               "truth: start (green), end (red)")
    for xs, ys, xe, ye in zip(t.x_start[lit], t.y_start[lit], t.x_end[lit], t.y_end[lit], strict=True):
        ax.plot([xs, xe], [ys, ye], color="gold", linewidth=0.4, alpha=0.6)
    ax.scatter(t.x_start[lit], t.y_start[lit], s=9, color="lime", linewidths=0)
    ax.scatter(t.x_end[lit], t.y_end[lit], s=9, color="red", linewidths=0)
    return _save(fig, path)


def plot_satellite_frame(sim: SimulatedImage, path: Path) -> Path:
    """The frame with the satellites' streaks marked and labelled, and the bright-body angles."""
    t, r = sim.truth, sim.truth.rsos
    flags = t.bright_bodies
    title = (f"satellite frame {t.time_mid.utc.isot[:19]} UTC; Sun {flags.sun_edge_deg:.0f} deg, "
             f"Moon {flags.moon_edge_deg:.0f} deg, Earth limb {flags.earth_edge_deg:.0f} deg from the boresight")
    fig, ax = _axes(sim.image, title)
    inside = t.inside()
    ax.scatter(t.x[inside], t.y[inside], s=60, facecolors="none", edgecolors="tab:cyan", linewidths=0.5)
    for k in np.flatnonzero(r.rendered):
        ax.annotate("", (r.x_end[k], r.y_end[k]), (r.x_start[k], r.y_start[k]),
                    arrowprops={"arrowstyle": "->", "color": "orange", "lw": 1.2})
        ax.annotate(f"RSO {r.ids[k]}: V {r.mag[k]:.1f}, {r.range_km[k]:.0f} km", (r.x_start[k], r.y_start[k]),
                    xytext=(8, 12), textcoords="offset points", color="orange", fontsize=8)
    return _save(fig, path)


def satellite_scene() -> OrbitalScene:
    """An observer in a 600 km polar orbit and a lit satellite 800 km above and ahead of it on a
    crossing orbit (circular speed, 110 deg from the observer's direction of motion), Lambertian
    (2.5 m radius, albedo 0.3)."""
    observer = Orbit.from_elements(EPOCH, KeplerElements.from_degrees(6978.0, 0.0, 97.8, 270.0, 0.0, 100.0))
    up = observer.r_km / np.linalg.norm(observer.r_km)
    along = observer.v_km_s / np.linalg.norm(observer.v_km_s)
    r = observer.r_km + 800.0 * up + 600.0 * along
    side = np.cross(up, along)
    speed = np.sqrt(MU_EARTH_KM3_S2 / np.linalg.norm(r))
    v = speed * (np.cos(np.radians(110.0)) * along + np.sin(np.radians(110.0)) * side)
    return OrbitalScene(observer, (RSO(Orbit(EPOCH, r, v), ident=43013, radius_m=2.5, albedo=0.3),))


def render_gallery() -> dict[str, SimulatedImage]:
    """The three seeded frames."""
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.5)
    sky = SkyBackground(mag_arcsec2=22.0)
    point = simulate_frame(CAMERA, ORION, max_mag=7.5, sensor=sensor, sky_background=sky, rng=1)
    streak = simulate_frame(CAMERA, ORION, max_mag=7.5, sensor=sensor, sky_background=sky, rng=2,
                            rate_rad_s=(0.3 * DEG, 0.9 * DEG, 0.35 * DEG))
    scene = satellite_scene()
    snap = scene.snapshots(EPOCH)[0]
    ra, dec = vector_to_radec(snap.rso_r[0] - snap.observer_r)
    pointing = rotation_from_radec_roll(float(ra) + 0.5 * DEG, float(dec) - 0.3 * DEG, 0.4)
    satellite = simulate_frame(CAMERA, pointing, max_mag=7.5, sensor=sensor, sky_background=sky, rng=3,
                               timing=FrameTiming(epoch=EPOCH), orbital=scene)
    return {"point": point, "streak": streak, "satellite": satellite}


def write_gallery(folder: str | Path = DEFAULT_OUT) -> list[Path]:
    """Render the three frames and write their annotated PNGs to ``folder`` (created if missing)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    frames = render_gallery()
    return [plot_point_frame(frames["point"], folder / "point.png"),
            plot_streak_frame(frames["streak"], folder / "streak.png"),
            plot_satellite_frame(frames["satellite"], folder / "satellite.png")]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="scripts/gallery.py", description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help=f"output folder (default {DEFAULT_OUT})")
    args = parser.parse_args(argv)
    for path in write_gallery(args.out):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
