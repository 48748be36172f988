"""Run every benchmark in sequence with its defaults (``python3 tasks.py bench`` calls this).

1. ``lis_benchmark.py``: lost-in-space on seeded star lists, startrack beside cedar-solve;
2. ``image_path_benchmark.py``: read + detect + solve of 1024 x 1024 PNG frames;
3. ``database_report.py``: the pattern database's build time, size and memory (5-35 deg),
   beside cedar-solve's shipped one;
4. ``tracking_benchmark.py``: the Tracker over 1000-frame tumbles, step cost vs lost-in-space;
5. ``detect_accuracy.py``: every centroider against the Cramér-Rao bound, pixel-phase bias,
   detection quality of every threshold method;
6. ``detect_speed.py``: detection time and accuracy beside SEP and photutils, the predictive
   pass;
7. ``detect_huffman2006.py``: Huffman 2006's Table 4.2 (WS vs MLE) and Table 7.2 (pre-filter time),
   campaigns of their shipped specs;
8. ``detect_realdata.py``: detections on the real images against astrometry.net;
9. ``jpeg_quality.py``: the real images and simulated frames saved as JPEGs of qualities 40-95,
   solved with the detector's compression noise floor and without;
   ``photo_hazards.py``: the real images with captions, the Moon, hot pixels, trails and clouds;
   ``bayer_fits.py``: one-shot-colour (Bayer mosaic) FITS frames, read as a grey sensor's and as
   a mosaic;
10. ``attitude_benchmark.py``: every Wahba solver batched and one by one, beside scipy and ahrs
   (``benchmarks/.venv-ahrs``, created on first use);
11. ``streak_benchmark.py``: Sease 2013 Tables 3.1, 4.1, 4.2, 4.4 and Samaan 2002 Table 2;
12. ``simulate_benchmark.py``: simulator speed beside a plain per-pixel loop, Samaan 2002 Table 1,
    Huffman 2006 Tables 5.1 and 5.3 (campaigns of their shipped specs);
13. ``huffman2006_table82.py``: Huffman 2006's Table 8.2 (time to match a 14-frame sequence by method);
14. ``jacobs1995_matching.py``: Jacobs 1995's Tables 3-5 to 3-7 (lost-in-space matching trade).

The cedar-solve environment (``benchmarks/.venv-cedar``) and the SEP / photutils one
(``benchmarks/.venv-detectpeers``) are created first if needed. A benchmark
that fails is reported and the others still run; the exit status is 1 if any failed.
Arguments after ``--`` go to ``lis_benchmark.py`` (e.g. ``-- --trials 1000``).
"""

from __future__ import annotations

import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import attitude_benchmark  # noqa: E402
import bayer_fits  # noqa: E402
import calibration_benchmark  # noqa: E402
import database_report  # noqa: E402
import detect_accuracy  # noqa: E402
import detect_huffman2006  # noqa: E402
import detect_realdata  # noqa: E402
import detect_speed  # noqa: E402
import huffman2006_table82  # noqa: E402
import image_path_benchmark  # noqa: E402
import jacobs1995_matching  # noqa: E402
import jpeg_quality  # noqa: E402
import lis_benchmark  # noqa: E402
import photo_hazards  # noqa: E402
import simulate_benchmark  # noqa: E402
import streak_benchmark  # noqa: E402
import tracking_benchmark  # noqa: E402
from peers.cedar_env import ensure_cedar_env  # noqa: E402
from peers.detect_env import ensure_detect_env  # noqa: E402


def _run(name: str, func, argv: list[str]) -> bool:
    print(f"\n=== {name} {' '.join(argv)}", flush=True)
    t0 = time.perf_counter()
    try:
        code = func(argv)
    except Exception:  # report and go on with the next benchmark
        traceback.print_exc()
        code = 1
    print(f"=== {name} finished in {time.perf_counter() - t0:.0f} s (exit {code})", flush=True)
    return code == 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    lis_args = argv[argv.index("--") + 1:] if "--" in argv else argv
    ensure_cedar_env()
    ensure_detect_env()
    ok = [
        _run("lis_benchmark", lis_benchmark.main, lis_args),
        _run("image_path_benchmark", image_path_benchmark.main, []),
        _run("database_report", database_report.main, []),
        _run("tracking_benchmark", tracking_benchmark.main, []),
        _run("calibration_benchmark", calibration_benchmark.main, []),
        _run("detect_accuracy", detect_accuracy.main, []),
        _run("detect_speed", detect_speed.main, []),
        _run("detect_huffman2006", detect_huffman2006.main, []),
        _run("detect_realdata", detect_realdata.main, []),
        _run("jpeg_quality", jpeg_quality.main, []),
        _run("photo_hazards", photo_hazards.main, []),
        _run("bayer_fits", bayer_fits.main, []),
        _run("attitude_benchmark", attitude_benchmark.main, []),
        _run("streak_benchmark", streak_benchmark.main, []),
        _run("simulate_benchmark", simulate_benchmark.main, []),
        _run("huffman2006_table82", huffman2006_table82.main, []),
        _run("jacobs1995_matching", jacobs1995_matching.main, []),
    ]
    return 0 if all(ok) else 1


if __name__ == "__main__":
    sys.exit(main())
