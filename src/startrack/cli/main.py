"""The ``startrack`` command: one module per subcommand, each with ``main(argv) -> int``."""

from __future__ import annotations

import importlib
import sys

from ..errors import StartrackError

SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "solve": ("startrack.cli.solve_cmd", "solve an image lost-in-space (FITS, PNG, JPEG, TIFF)"),
    "solve-stars": ("startrack.cli.solve_stars_cmd", "solve a CSV star list (x, y in 0-based pixels)"),
    "simulate": ("startrack.cli.simulate_cmd", "simulate a star image with its truth"),
    "demo": ("startrack.cli.demo_cmd", "simulate a random sky image, solve it, compare with the truth"),
}

USAGE = "usage: startrack {" + ",".join(SUBCOMMANDS) + "} [options]\n\n" + "\n".join(
    f"  {name:<12} {text}" for name, (_, text) in SUBCOMMANDS.items()) + \
    "\n\nRun 'startrack COMMAND --help' for the options of a command."


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in {"-h", "--help"}:
        print(USAGE)
        return 0 if argv else 2
    name, rest = argv[0], argv[1:]
    if name not in SUBCOMMANDS:
        print(f"startrack: error: unknown command {name!r}\n{USAGE}", file=sys.stderr)
        return 2
    module = importlib.import_module(SUBCOMMANDS[name][0])
    try:
        return module.main(rest)
    except (StartrackError, ValueError, OSError) as exc:
        print(f"startrack {name}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"startrack {name}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
