"""The argument parser of every subcommand: argparse's, taking any negative number for a value.

argparse tells an option from a value by its leading "-", and reads a negative number as a value
only when it matches its own pattern of digits: ``-5`` and ``-0.25``, not ``-1e9``, ``-2.5E-3``,
``-1e400`` or ``-inf``, which it took for unknown options and answered "expected one argument"
(``--epoch -1e9``, ``--height-m -1e3``). :class:`CommandParser` widens that pattern to every number
``float`` reads with a sign (exponents, ``inf``, ``infinity``, ``nan``), so that the option's own
type and check judge the value as typed ("--epoch must be a finite number, got -inf"). Python
3.14 widened argparse's own pattern to exponents (CPython gh-124823), not to ``inf``. The
attribute set is argparse's (``_negative_number_matcher``); a Python whose argparse reads
another one parses as its argparse does.
"""

from __future__ import annotations

import argparse
import re

NEGATIVE_NUMBER = re.compile(r"^-((\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE)
"""A negative number as ``float`` reads it: digits with an optional fraction and exponent, or
``inf``, ``infinity``, ``nan`` in any case."""


class CommandParser(argparse.ArgumentParser):
    """:class:`argparse.ArgumentParser` that reads every negative number (:data:`NEGATIVE_NUMBER`)
    as a value; its sub-parsers (``add_subparsers``) are of this class too."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER
