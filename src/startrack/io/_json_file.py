"""Reading a user's JSON file (a rig, a rig's camera file, a tracker noise model) with one clear error.

JSON is UTF-8 (RFC 8259 §8.1), so the file is decoded as UTF-8 whatever the locale says. A file that
is missing, unreadable, not UTF-8 text (an image given where JSON was asked for) or not JSON raises
:class:`~startrack.errors.InvalidInputError` naming what the file was for, the file and the problem,
so that the command line reports it as bad input (exit status 2), not as a fault of startrack's.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError


def read_json_file(path: str | os.PathLike, what: str) -> Any:
    """The JSON value in the file ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for the message ("rig file", "tracker noise model").

    Returns
    -------
    Any
        The decoded value (dict, list, str, number, bool or None).

    Raises
    ------
    InvalidInputError
        The file cannot be read, is not UTF-8 text or is not valid JSON, or holds what Python's
        decoder refuses outside its own errors (an integer of more than
        ``sys.get_int_max_str_digits()`` digits, arrays nested thousands deep).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"{what} {path} is not JSON text: byte {exc.start} is not UTF-8 "
                                "(is it an image or another binary file?)") from None
    except OSError as exc:
        raise InvalidInputError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidInputError(f"{what} {path} is not valid JSON: {exc}") from None
    except ValueError:  # the decoder's limit on an integer's digits (not a JSONDecodeError)
        raise InvalidInputError(f"{what} {path} holds an integer of more than {sys.get_int_max_str_digits()} "
                                "digits; valid: numbers of ordinary size") from None
    except RecursionError:
        raise InvalidInputError(f"{what} {path} nests arrays or objects too deeply to read; a {what} is "
                                "only a few levels deep") from None
