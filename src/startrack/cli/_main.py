"""The ``startrack`` command: one module per subcommand, each with ``main(argv) -> int``.

Exit status: 0 success, 1 an expected failure reported as a result (e.g. not solved: too few
stars, no match), 2 misuse (bad option, unreadable or invalid input), reported as one line
``startrack <cmd>: error: <message>`` on standard error with no traceback (argparse's own
errors print the usage line first), 3 an unexpected error: a fault of startrack's, one line
naming the exception's type (:data:`DEBUG_ENV` set to 1 shows its traceback).
"""

from __future__ import annotations

import importlib
import os
import sys

from .. import __version__
from ..errors import StartrackError

DEBUG_ENV = "STARTRACK_DEBUG"
"""Set to 1, an unexpected error raises with its traceback instead of its one line (exit 3)."""
INTERNAL_ERROR = 3
"""Exit status of an unexpected error (a fault of startrack's)."""

SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "solve": ("startrack.cli._solve_cmd", "solve an image lost-in-space (FITS, PNG, JPEG, TIFF)"),
    "solve-stars": ("startrack.cli._solve_stars_cmd", "solve a CSV star list (x, y in 0-based pixels)"),
    "solve-rig": ("startrack.cli._solve_rig_cmd", "one attitude from the images or star lists of several camera heads"),
    "detect": ("startrack.cli._detect_cmd", "detect and centroid the stars of an image"),
    "simulate": ("startrack.cli._simulate_cmd", "simulate a star image with its truth"),
    "track": ("startrack.cli._track_cmd", "follow the attitude over a sequence of images, write a CSV"),
    "rate": ("startrack.cli._rate_cmd", "angular rate from a streaked image or an image pair (no catalog)"),
    "calibrate": ("startrack.cli._calibrate_cmd", "calibrate a camera from star or checkerboard images"),
    "availability": ("startrack.cli._availability_cmd", "stars in the field over random pointings (histogram)"),
    "demo": ("startrack.cli._demo_cmd", "simulate a random sky image, solve it, compare with the truth"),
    "campaign": ("startrack.cli._campaign_cmd", "Monte Carlo campaigns from a TOML spec: run, report, rerun, list"),
    "analyse": ("startrack.cli._analyse_cmd", "post-processing analyses over result sets (figures + CSV)"),
    "adcs-demo": ("startrack.cli._adcs_cmd", "closed-loop attitude control with the star tracker in the loop"),
    "web": ("startrack.cli._web_cmd", "the browser tool: a local server with pages and a JSON API"),
    "warm-up": ("startrack.cli._batch_warmup", "build the default database and compile the solver (once)"),
}

USAGE = "usage: startrack {" + ",".join(SUBCOMMANDS) + "} [options]\n\n" + "\n".join(
    f"  {name:<12} {text}" for name, (_, text) in SUBCOMMANDS.items()) + \
    "\n\nRun 'startrack COMMAND --help' for the options of a command.\n" \
    "Exit status: 0 success, 1 not solved (the reason is printed), 2 misuse, 3 a fault of startrack's."


def one_line(exc: BaseException) -> str:
    """The exception's message on one line (its class name when it has none)."""
    return " ".join(str(exc).split()) or type(exc).__name__


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] in {"-h", "--help"}:
        print(USAGE)
        return 0
    if argv and argv[0] == "--version":
        print(f"startrack {__version__}")
        return 0
    if not argv or argv[0] not in SUBCOMMANDS:
        problem = f"unknown command {argv[0]!r}" if argv else "a command is required"
        print(f"{USAGE}\nstartrack: error: {problem}", file=sys.stderr)
        return 2
    return _run(argv[0], argv[1:])


def _run(name: str, argv: list[str]) -> int:
    from ._process_gc import collection_paused
    from ._run_context import Terminated, command_context, memory_message

    with collection_paused():  # the subcommand's modules live as long as the process
        module = importlib.import_module(SUBCOMMANDS[name][0])
    try:
        with command_context(name):  # inputs protected, SIGTERM raises Terminated, one-line warnings
            return module.main(argv)
    except Terminated as exc:  # outputs already cleaned up by their finally blocks
        print(f"startrack {name}: terminated", file=sys.stderr)
        return exc.code if isinstance(exc.code, int) else 1
    except SystemExit as exc:  # argparse: --help (0) or a usage error (2, already printed)
        return exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    except BrokenPipeError:  # e.g. `startrack solve x.fits --json | head`: stop quietly, as on SIGPIPE
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except MemoryError as exc:
        print(f"startrack {name}: error: {memory_message(exc)}", file=sys.stderr)
        return 2
    except (StartrackError, OSError) as exc:
        print(f"startrack {name}: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"startrack {name}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if os.environ.get(DEBUG_ENV) == "1":
            raise
        print(f"startrack {name}: error: unexpected {type(exc).__name__} (a fault of startrack's, please report it; "
              f"{DEBUG_ENV}=1 shows where): {one_line(exc)}", file=sys.stderr)
        return INTERNAL_ERROR


if __name__ == "__main__":
    sys.exit(main())
