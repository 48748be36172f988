"""The bad inputs of issue 17's probe, run through the command line and the Python API, as a table.

Each case builds its input in a temporary folder, runs ``startrack ...`` in a new process (the
real command: its exit status, its one line on standard error) or calls the library, and prints
one Markdown row: the case, what was run, the exit status (or the exception's class) and the
message, with the temporary folder's path shortened to ``TMP``. Exit status 0 solved or written,
1 not solved, 2 refused (``docs/io.md``). The regression tests of these cases are in
``tests/io``, ``tests/cli`` and the stage test folders; this script only shows what a user sees.

    .venv/bin/python scripts/bad_inputs.py [--out TABLE.md]
"""

from __future__ import annotations

import argparse
import csv
import gzip
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from startrack import Camera, solve_image, solve_stars
from startrack.io import write_fits

HERE = Path(__file__).resolve().parent
STARTRACK = Path(sys.executable).with_name("startrack")


COMMANDS = (
    ("a header claiming 100,000 x 100,000 px", "solve claims.fits"),
    ("a 1.5 MB gzip FITS of a 20,000 x 20,000 float64 image", "solve bomb.fits.gz"),
    ("a sparse 3 GiB file", "solve sparse.bin"),
    ("pixel values near 1e300", "solve huge_values.fits"),
    ("the output over the input", "solve frame.fits --wcs frame.fits"),
    ("a track output over an input frame", "track seq --fov-deg 15 --out seq/frame_00000.fits"),
    ("a billion-pixel simulation", "simulate --width 1000000000 --out big.fits"),
    ("a 1e6 px PSF", "simulate --psf-sigma-px 1e6 --out wide.fits"),
    ("a star-list field of 200,000 characters", "solve-stars long_field.csv --width 512 --height 512"),
    ("a time that is not a time", "solve frame.fits --time garbage"),
    ("a NaN magnitude limit", "availability --fov-deg 15 --max-mag nan"),
    ("an infinite frame interval", "track seq --fov-deg 15 --frame-interval-s inf"),
    ("a negative field of view", "solve frame.fits --fov-deg -5"),
    ("a pixel limit the image exceeds", "solve frame.fits --max-pixels 1000"),
)
"""(case, the command's arguments) of the cases that only run the command, in the folder of
:func:`cli_cases`'s inputs."""


def _fits_header_only(width: int, height: int, bitpix: int) -> bytes:
    cards = [f"SIMPLE  = {'T':>20}", f"BITPIX  = {bitpix:>20}", f"NAXIS   = {2:>20}",
             f"NAXIS1  = {width:>20}", f"NAXIS2  = {height:>20}", "END"]
    return "".join(card.ljust(80) for card in cards).ljust(2880).encode("ascii")


def _frame(tmp: Path) -> Path:
    """A small simulated frame that solves (the command's own simulator)."""
    path = tmp / "frame.fits"
    if not path.exists():
        subprocess.run([str(STARTRACK), "simulate", "--fov-deg", "15", "--width", "512", "--height", "512",
                        "--seed", "3", "--out", str(path)], check=True, capture_output=True)
    return path


def _cli(tmp: Path, *args: str | Path) -> tuple[str, str]:
    """Run the command; (exit status, its last line of standard error or first of output)."""
    out = subprocess.run([str(STARTRACK), *map(str, args)], capture_output=True, text=True, timeout=600, cwd=tmp)
    text = out.stderr.strip().splitlines() or out.stdout.strip().splitlines() or [""]
    message = text[-1] if out.stderr.strip() else text[0]
    return str(out.returncode), message.replace(str(tmp), "TMP")


def _api(call: Callable[[], object]) -> tuple[str, str]:
    """Call the library; (the exception's class or "returned", its message or the result's status)."""
    try:
        result = call()
    except (TypeError, ValueError) as exc:
        return type(exc).__name__, str(exc)
    status = getattr(result, "status", None)
    return "returned", f"status {status.value}: {getattr(result, 'reason', '')}" if status else repr(result)


def _track_past_garbage(tmp: Path) -> tuple[str, str]:
    """``track`` over two good frames and a garbage one: the garbage frame's row of the CSV."""
    status, _ = _cli(tmp, "track", "seq", "--fov-deg", "15", "--out", "track.csv")
    with open(tmp / "track.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    bad = rows[-1]
    return status, (f"{len(rows)} rows written ({sum(r['status'] == 'ok' for r in rows)} ok); {bad['file']}: "
                    f"status {bad['status']}, reason {bad['reason']!r}".replace(str(tmp), "TMP"))


def _through_fifo(tmp: Path) -> tuple[str, str]:
    """``--wcs`` to a FIFO that ``cat`` reads: the WCS goes through it and the FIFO stays one."""
    reader = subprocess.Popen(["cat", str(tmp / "pipe")], stdout=subprocess.PIPE)
    status, message = _cli(tmp, "solve", "frame.fits", "--wcs", "pipe")
    got = reader.communicate(timeout=60)[0]
    still = "still a FIFO" if (tmp / "pipe").is_fifo() else "replaced by a file"
    return status, f"{message}; {len(got)} bytes read from the FIFO, {still}"


def cli_cases(tmp: Path) -> list[tuple[str, str, tuple[str, str]]]:
    """(case, command as shown, (exit status, message)) for each command-line case."""
    frame = _frame(tmp)
    (tmp / "claims.fits").write_bytes(_fits_header_only(100_000, 100_000, 16))
    with gzip.open(tmp / "bomb.fits.gz", "wb") as fh:
        fh.write(_fits_header_only(20_000, 20_000, -64) + bytes(8 << 20))
    with open(tmp / "sparse.bin", "wb") as fh:
        fh.truncate(3 << 30)
    write_fits(tmp / "huge_values.fits", np.full((16, 16), 1e300))
    (tmp / "long_field.csv").write_text("x,y\n" + "1" * 200_000 + ",2\n")
    os.mkfifo(tmp / "pipe")
    seq = tmp / "seq"
    seq.mkdir()
    for k in range(2):
        (seq / f"frame_0000{k}.fits").write_bytes(frame.read_bytes())
    (seq / "frame_00002.fits").write_bytes(b"garbage")
    plain = [(case, command, _cli(tmp, *command.split())) for case, command in COMMANDS]
    return plain + [
        ("a garbage frame in a sequence", "track seq --fov-deg 15 --out track.csv", _track_past_garbage(tmp)),
        ("a FIFO as the output (a reader on it)", "solve frame.fits --wcs pipe", _through_fifo(tmp)),
    ]


def api_cases() -> list[tuple[str, str, tuple[str, str]]]:
    """(case, call as shown, (exception class or "returned", message)) for each library case."""
    x = np.ma.masked_array([10.0, 200.0, 300.0, 400.0], mask=[False, True, False, False])
    y = np.array([10.0, 50.0, 300.0, 100.0])
    return [
        ("options of the wrong type", "solve_stars(x, y, width=512, height=512, options='fast')",
         _api(lambda: solve_stars(y, y, width=512, height=512, options="fast"))),
        ("a camera that is not a Camera", "solve_stars(x, y, camera='imx219')",
         _api(lambda: solve_stars(y, y, camera="imx219"))),
        ("a detector that is not a StarDetector", "solve_image(image, detector={'sigma': 4})",
         _api(lambda: solve_image(np.zeros((64, 64)), detector={"sigma": 4}))),
        ("a prior that is not a Rotation", "solve_stars(..., method='overlay', prior_rot_cam_from_icrs=[0, 0, 0, 1])",
         _api(lambda: solve_stars(y, y, width=512, height=512, fov_deg=10, method="overlay",
                                  prior_rot_cam_from_icrs=[0, 0, 0, 1]))),
        ("a masked star list", "solve_stars(masked x, y, width=512, height=512)",
         _api(lambda: solve_stars(x, y, width=512, height=512))),
        ("a negative pixel pitch", "Camera.from_fov(512, 512, 10, pixel_pitch_um=-3)",
         _api(lambda: Camera.from_fov(512, 512, 10.0, pixel_pitch_um=-3.0))),
        ("guided not a boolean", "solve_image(image, guided='yes')",
         _api(lambda: solve_image(np.zeros((64, 64)), guided="yes"))),
    ]


def table(rows: list[tuple[str, str, tuple[str, str]]], what: str) -> str:
    lines = [f"| case | {what} | exit / raised | message |", "| --- | --- | --- | --- |"]
    for case, call, (status, message) in rows:
        lines.append(f"| {case} | `{call}` | {status} | {message.replace('|', '/')} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="also write the tables to this Markdown file")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        text = table(cli_cases(Path(folder)), "command") + "\n\n" + table(api_cases(), "call")
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
