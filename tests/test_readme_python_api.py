"""The README's Python API example runs as printed and solves: before, it simulated with the
default sensor preset at 0.1 s, which leaves one to three detectable stars, and every solve said
too_few_stars; and its last line used names it never defined."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from startrack import Status

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_api_block() -> str:
    """The first ```python block after the '## The Python API' heading."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("## The Python API"):]
    start = section.index("```python\n") + len("```python\n")
    return section[start: section.index("```", start)]


def test_the_python_api_example_solves_as_printed():
    names: dict = {}
    with contextlib.redirect_stdout(io.StringIO()) as out:
        exec(compile(_python_api_block(), str(README), "exec"), names)  # noqa: S102  # our own README
    assert names["solution"].status is Status.OK  # the last solve, from the detections as a star list
    assert out.getvalue().startswith("Status.OK")  # the first one, from the image
