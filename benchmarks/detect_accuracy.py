"""Centroid accuracy against the Cramér-Rao bound, pixel-phase bias, and detection quality.

1. **RMS error / CRB** of every centroider, through the whole detector (``detect(frame,
   centroid=...)``), on seeded frames of equal stars at integrated SNR 5-500 (PSF sigma 1.5 px,
   100 e- background, 5 e- read noise, uniformly random sub-pixel positions). The bound is
   :func:`startrack.detect.crb_sigma_px` for each star's own phase with flux and background
   unknown; the ratio is the RMS error over the matched stars divided by the RMS bound. Also the
   completeness and how well each method's ``sigma_px`` predicts its error. Writes the plot
   ``docs/detection_crb.png``.
2. **Pixel-phase bias**: the mean x error against the sub-pixel phase at SNR 300, for an
   undersampled (0.7 px) and a sampled (1.5 px) PSF; with the weighted sum also over only the
   3 x 3 pixels around the brightest, the classic small-window centroid whose cut wings give
   Huffman 2006's S-curve bias.
3. **Detection quality** of each threshold method on frames of stars from SNR 3 to 100:
   completeness per SNR (magnitude) bin and false detections per frame, and detections on
   pure-noise frames.

    .venv/bin/python benchmarks/detect_accuracy.py [--frames 3] [--no-plot]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from detect_frames import (  # noqa: E402
    BACKGROUND_E,
    READ_NOISE_E,
    crb_of,
    grid_positions,
    match,
    render_frame,
    snr_frame,
)

from startrack.detect import StarDetector  # noqa: E402
from startrack.detect import _crb as crb

SHAPE = (512, 512)
SNRS = (5, 10, 20, 50, 100, 200, 500)
PSF_SIGMA_PX = 1.5
DOCS = Path(__file__).resolve().parents[1] / "docs"


def methods(psf_sigma_px: float) -> dict[str, StarDetector]:
    """The centroiders compared, by label (``windowed`` is the detector's default)."""
    return {
        "peak": StarDetector(centroid="peak"),
        "area": StarDetector(centroid="area"),
        "weighted": StarDetector(centroid="weighted"),
        "weighted-raw": StarDetector(centroid="weighted-raw"),
        "windowed (default)": StarDetector(),
        "mle": StarDetector(centroid="mle"),
        "mle, psf known": StarDetector(centroid="mle", psf_sigma_px=psf_sigma_px),
        "mle, gain known": StarDetector(centroid="mle", gain_e_per_adu=1.0),
    }


def crb_table(n_frames: int, seed: int) -> dict[str, np.ndarray]:
    """RMS / CRB, completeness and sigma_px / RMS per method and SNR; prints the tables."""
    detectors = methods(PSF_SIGMA_PX)
    ratio = {name: np.full(len(SNRS), np.nan) for name in detectors}
    complete = {name: np.full(len(SNRS), np.nan) for name in detectors}
    honesty = {name: np.full(len(SNRS), np.nan) for name in detectors}
    bounds = np.zeros(len(SNRS))
    for k, snr in enumerate(SNRS):
        rng = np.random.default_rng(seed + k)
        frames = [snr_frame(SHAPE, snr, PSF_SIGMA_PX, rng) for _ in range(n_frames)]
        bound_all = np.concatenate([crb_of(f) for f in frames])
        bounds[k] = np.sqrt(np.mean(bound_all**2))
        for name, detector in detectors.items():
            err, sig, found, bnd = [], [], 0, []
            for frame, b in zip(frames, np.split(bound_all, n_frames), strict=True):
                det = detector.detect(frame.image)
                idx, ok = match(frame.x, frame.y, det.x, det.y)
                found += ok.sum()
                err.append(np.concatenate([det.x[idx[ok]] - frame.x[ok], det.y[idx[ok]] - frame.y[ok]]))
                sig.append(np.tile(det.sigma_px[idx[ok]], 2))
                bnd.append(np.tile(b[ok], 2))
            err, sig, bnd = np.concatenate(err), np.concatenate(sig), np.concatenate(bnd)
            if err.size:
                rms = np.sqrt(np.mean(err**2))
                ratio[name][k] = rms / np.sqrt(np.mean(bnd**2))
                honesty[name][k] = np.sqrt(np.mean(sig**2)) / rms
            complete[name][k] = found / sum(f.x.size for f in frames)
    _print_grid("RMS centroid error / Cramér-Rao bound (flux and background unknown)", ratio)
    print("CRB (px):      " + " ".join(f"{b:7.4f}" for b in bounds))
    _print_grid("completeness (fraction of stars detected within 2 px)", complete)
    _print_grid("reported sigma_px / measured RMS error", honesty)
    return {"ratio": ratio, "bounds": bounds}


def _print_grid(title: str, table: dict[str, np.ndarray]) -> None:
    print(f"\n{title}, PSF sigma {PSF_SIGMA_PX} px, {BACKGROUND_E:.0f} e- sky, "
          f"{READ_NOISE_E:.0f} e- read noise")
    print(f"{'method':<20}" + "".join(f"{'SNR ' + str(s):>9}" for s in SNRS))
    for name, values in table.items():
        print(f"{name:<20}" + "".join(f"{v:9.2f}" for v in values))


def plot(result: dict, path: Path) -> None:
    """RMS / CRB against SNR for every method, and the bound itself."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, values in result["ratio"].items():
        ax.plot(SNRS, values, marker="o", label=name, lw=2.5 if "default" in name else 1.2)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhspan(1.0, 1.2, color="g", alpha=0.08)
    ax.set(xscale="log", yscale="log", xlabel="integrated SNR", ylabel="RMS error / CRB",
           title=f"Centroiders against the Cramér-Rao bound (PSF sigma {PSF_SIGMA_PX} px)")
    ax.legend(fontsize=7)
    snr = np.geomspace(3, 1000, 60)
    for sigma in (0.7, 1.5, 2.5):
        flux = crb.flux_for_snr(snr, sigma, BACKGROUND_E, READ_NOISE_E)
        ax2.plot(snr, crb.crb_sigma_px(flux, sigma, BACKGROUND_E, READ_NOISE_E),
                 label=f"PSF sigma {sigma} px")
    ax2.set(xscale="log", yscale="log", xlabel="integrated SNR", ylabel="CRB per axis (px)",
            title="The bound: 100 e- sky, 5 e- read noise")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"\nplot written to {path}")


def phase_bias(seed: int) -> None:
    """Mean x error in bins of the sub-pixel x phase, at SNR 300."""
    edges = np.linspace(-0.5, 0.5, 11)
    print("\nmean x error (px) against the sub-pixel phase of x, SNR 300")
    for sigma in (0.7, 1.5):
        rng = np.random.default_rng(seed)
        frames = [snr_frame(SHAPE, 300.0, sigma, rng, spacing=32) for _ in range(3)]
        print(f"PSF sigma {sigma} px; phase bin centres: "
              + " ".join(f"{c:+6.2f}" for c in 0.5 * (edges[1:] + edges[:-1])))
        for name, detector in {**methods(sigma), "weighted, 3 x 3 box": None}.items():
            if name in ("peak", "area", "mle, gain known"):
                continue
            errs, phases = [], []
            for frame in frames:
                det = box3_centroids(frame.image) if detector is None else detector.detect(frame.image)
                idx, ok = match(frame.x, frame.y, det.x, det.y)
                errs.append(det.x[idx[ok]] - frame.x[ok])
                phases.append(frame.x[ok] - np.rint(frame.x[ok]))
            errs, phases = np.concatenate(errs), np.concatenate(phases)
            which = np.clip(np.digitize(phases, edges) - 1, 0, 9)
            bias = [errs[which == b].mean() for b in range(10)]
            print(f"  {name:<20}" + " ".join(f"{b:+6.3f}" for b in bias)
                  + f"   max |bias| {np.max(np.abs(bias)):.3f}")


def box3_centroids(image: np.ndarray):
    """The classic weighted sum over the 3 x 3 pixels around each default detection's
    brightest pixel (background subtracted): its truncated wings give Huffman 2006's S-curve."""
    from startrack.detect._windows import extract_windows
    det = StarDetector().detect(image)
    win = extract_windows(image, np.rint(det.x), np.rint(det.y), 3)
    peak = win.values[:, 1:-1, 1:-1].reshape(len(det), -1).argmax(axis=1)
    cy, cx = np.divmod(peak, 5)
    cx, cy = win.x0 + 1 + cx, win.y0 + 1 + cy
    box = extract_windows(image, cx, cy, 1)
    w = np.maximum(box.values - det.background, 0.0)
    xs, ys = box.coords()
    total = w.sum(axis=(1, 2))
    return type(det)(x=(w * xs).sum(axis=(1, 2)) / total, y=(w * ys).sum(axis=(1, 2)) / total)


THRESHOLDS = {
    "ksigma local (tiled)": {},
    "ksigma global": {"background": "global"},
    "dynamic": {"threshold": "dynamic"},
    "prefilter-window k=3": {"threshold": "prefilter-window", "pixel_sigma": 3.0},
    "prefilter-grid k=3": {"threshold": "prefilter-grid", "pixel_sigma": 3.0},
    "prefilter-window k=2": {"threshold": "prefilter-window", "pixel_sigma": 2.0},
}


def detection_quality(n_frames: int, seed: int) -> None:
    """Completeness per SNR bin and false detections per frame, per threshold method."""
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(n_frames):
        x, y = grid_positions(SHAPE, 48, rng)
        snr = np.exp(rng.uniform(np.log(3.0), np.log(100.0), x.size))
        flux = crb.flux_for_snr(snr, PSF_SIGMA_PX, BACKGROUND_E, READ_NOISE_E)
        frames.append((render_frame(SHAPE, x, y, flux, PSF_SIGMA_PX, rng), snr))
    noise_frames = [render_frame(SHAPE, np.zeros(0), np.zeros(0), np.zeros(0), PSF_SIGMA_PX, rng)
                    for _ in range(n_frames)]
    edges = np.array([3, 4, 5, 6, 8, 10, 15, 25, 100])
    print("\ndetection quality: completeness per integrated-SNR bin (instrument magnitude "
          "-2.5 log10 flux in brackets), false detections per frame with stars, detections "
          "per pure-noise frame")
    mags = -2.5 * np.log10(crb.flux_for_snr(np.sqrt(edges[:-1] * edges[1:]), PSF_SIGMA_PX,
                                            BACKGROUND_E, READ_NOISE_E))
    print(f"{'threshold':<22}" + "".join(f"{f'{a}-{b}':>8}" for a, b in zip(edges[:-1], edges[1:],
                                                                        strict=True))
          + f"{'false':>8}{'noise':>8}")
    print(f"{'':<22}" + "".join(f"{f'({m:.1f})':>8}" for m in mags))
    for name, settings in THRESHOLDS.items():
        found_snr, all_snr, false = [], [], 0
        for frame, snr in frames:
            kw = dict(settings)
            if kw.get("threshold") == "dynamic":
                kw["target_stars"] = frame.x.size
            det = StarDetector(**kw).detect(frame.image)
            idx, ok = match(frame.x, frame.y, det.x, det.y)
            found_snr.append(snr[ok])
            all_snr.append(snr)
            false += len(det) - ok.sum()
        noise = np.mean([len(StarDetector(**settings).detect(f.image)) for f in noise_frames])
        hit = np.histogram(np.concatenate(found_snr), edges)[0]
        tot = np.histogram(np.concatenate(all_snr), edges)[0]
        print(f"{name:<22}" + "".join(f"{h / max(t, 1):8.2f}" for h, t in zip(hit, tot, strict=True))
              + f"{false / len(frames):8.1f}{noise:8.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=3, help="frames per SNR (default 3)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args(argv)
    result = crb_table(args.frames, args.seed)
    if not args.no_plot:
        plot(result, DOCS / "detection_crb.png")
    phase_bias(args.seed + 100)
    detection_quality(2 * args.frames, args.seed + 200)
    return 0


if __name__ == "__main__":
    sys.exit(main())
