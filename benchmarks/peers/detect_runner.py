"""Run SEP and photutils' DAOStarFinder on frames; runs inside ``benchmarks/.venv-detectpeers``.

Must not import startrack. Reads ``frames`` (K, H, W) and ``psf_sigma_px`` from an ``.npz``,
writes per method the detections of every frame (``<m>_x``, ``<m>_y``, ``<m>_flux``,
``<m>_frame``), the median time per frame over ``--repeats`` runs (``<m>_time_s``, shape (K,))
and the fastest run (``<m>_best_s``), by the wall clock or, with ``--clock cpu``, by the CPU time
of the process (``time.process_time``). Both peers use the 0-based pixel-centre
convention of startrack.

* ``sep``: ``sep.Background`` (64 px boxes, 3 x 3 filter, SExtractor's defaults) and
  ``sep.extract`` at 5 times the background's global RMS with its default 3 x 3 conv kernel
  and deblending; positions are SEP's isophotal barycentres (``x``, ``y``).
* ``sep_win``: the same detections refined by ``sep.winpos`` (SExtractor's XWIN / YWIN, a
  Gaussian-windowed centroid), timed as extract + winpos.
* ``dao``: ``sigma_clipped_stats`` (3 sigma) for the background and noise, then
  ``DAOStarFinder(threshold=5 * std, fwhm=2.3548 * psf_sigma_px)`` on the
  background-subtracted frame; positions are its ``xcentroid``, ``ycentroid``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def _sep(frame: np.ndarray, psf_sigma_px: float, windowed: bool):
    import sep
    data = frame.astype(np.float32)
    bkg = sep.Background(data)
    sub = data - bkg
    objs = sep.extract(sub, 5.0, err=bkg.globalrms)
    x, y, flux = objs["x"], objs["y"], objs["flux"]
    if windowed and len(objs):
        x, y, _ = sep.winpos(sub, x, y, np.full(len(objs), psf_sigma_px))
    return x, y, flux


def _dao(frame: np.ndarray, psf_sigma_px: float):
    from astropy.stats import sigma_clipped_stats
    from photutils.detection import DAOStarFinder
    data = frame.astype(np.float32)
    _, median, std = sigma_clipped_stats(data, sigma=3.0)
    table = DAOStarFinder(threshold=5.0 * std, fwhm=2.3548 * psf_sigma_px)(data - median)
    if table is None:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    names = ("x_centroid", "y_centroid") if "x_centroid" in table.colnames else \
        ("xcentroid", "ycentroid")
    return (np.asarray(table[names[0]], float), np.asarray(table[names[1]], float),
            np.asarray(table["flux"], float))


METHODS = {
    "sep": lambda f, s: _sep(f, s, False),
    "sep_win": lambda f, s: _sep(f, s, True),
    "dao": _dao,
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("frames_npz")
    parser.add_argument("out_npz")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    args = parser.parse_args(argv)
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    with np.load(args.frames_npz) as npz:
        frames, sigma = npz["frames"], float(npz["psf_sigma_px"])
    out = {}
    for name, run in METHODS.items():
        run(frames[0], sigma)  # warm-up (imports, caches)
        xs, ys, fs, ks, times, best = [], [], [], [], [], []
        for k, frame in enumerate(frames):
            samples = []
            for _ in range(args.repeats):
                t0 = clock()
                x, y, flux = run(frame, sigma)
                samples.append(clock() - t0)
            times.append(float(np.median(samples)))
            best.append(float(np.min(samples)))
            xs.append(x)
            ys.append(y)
            fs.append(flux)
            ks.append(np.full(len(x), k))
        out.update({f"{name}_x": np.concatenate(xs), f"{name}_y": np.concatenate(ys),
                    f"{name}_flux": np.concatenate(fs), f"{name}_frame": np.concatenate(ks),
                    f"{name}_time_s": np.array(times), f"{name}_best_s": np.array(best)})
    import photutils
    import sep
    out["versions"] = np.array([sep.__version__, photutils.__version__])
    np.savez(args.out_npz, **out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
