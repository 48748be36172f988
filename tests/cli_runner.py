"""The command line run in-process by the tests: ``startrack ARGV`` without a new interpreter."""

from __future__ import annotations

import contextlib
import io

from startrack.cli import main


def run(*argv: object) -> tuple[int, str, str]:
    """Run ``startrack ARGV`` (each argument as ``str``) in this process; returns (exit code,
    stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()
