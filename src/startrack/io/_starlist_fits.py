"""Star lists as FITS tables: astrometry.net's xylists (``image2xy``, ``solve-field``'s ``.axy``)
and SExtractor's ``FITS_LDAC`` catalogs.

The first table extension that holds a pair of position columns (as :mod:`._starlist` names them)
is read; an ``LDAC_IMHEAD`` extension before it, which holds the image's header as text, is
passed over. Columns of one number per row are kept, a vector column (``FLUX_APER`` of several
apertures) gives its first element. FITS tables give positions in FITS pixel coordinates: ``X`` and ``Y``
(astrometry.net says so in its xylists' header: "1,1 is the center of the leftmost bottom pixel")
are 1-based like SExtractor's ``X_IMAGE``; :mod:`._starlist` subtracts 1.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

FITS_SIGNATURE = b"SIMPLE  ="
"""The first bytes of every FITS file."""


def is_fits(path: Path) -> bool:
    """Whether ``path`` starts as a FITS file does."""
    with open(path, "rb") as fh:
        return fh.read(len(FITS_SIGNATURE)) == FITS_SIGNATURE


def image_size(path: str | os.PathLike) -> tuple[int, int] | None:
    """The (width, height) in pixels of the image a FITS star list was measured on, as
    astrometry.net's ``.axy`` files give it (``IMAGEW``, ``IMAGEH`` in the primary header); None
    for another file, or one without both (positive integers)."""
    try:
        if not is_fits(Path(path)):
            return None
        from astropy.io import fits  # here: a CSV needs none of it

        header = fits.getheader(path, 0)
    except (OSError, ValueError):
        return None
    size = tuple(header.get(key) for key in ("IMAGEW", "IMAGEH"))
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and v >= 1 and float(v).is_integer()
               for v in size):
        return None
    return int(size[0]), int(size[1])


def read_fits_table(path: Path, has_positions: Callable[[list[str]], bool], max_rows: int
                    ) -> tuple[list[str], NDArray[np.float64], NDArray[np.bool_]]:
    """The column names (lower case), values (N, K) and whether each column holds numbers (K,)
    of the first table in ``path`` whose names ``has_positions`` accepts.

    Raises
    ------
    InvalidInputError
        The file is not valid FITS, none of its tables has position columns (naming the
        columns of each table), or the table has more than ``max_rows`` rows.
    """
    from astropy.io import fits

    with warnings.catch_warnings():
        warnings.simplefilter("error", fits.verify.VerifyWarning)  # a truncated file: refused, not half read
        try:
            with fits.open(path, memmap=False) as hdus:
                tables = [hdu for hdu in hdus[1:] if isinstance(hdu, fits.BinTableHDU | fits.TableHDU)]
                for hdu in tables:
                    names = [name.strip().lower() for name in hdu.columns.names]
                    if has_positions(names):
                        return _table_values(path, hdu, names, max_rows)
        except (OSError, ValueError, TypeError, fits.verify.VerifyWarning) as exc:
            raise InvalidInputError(f"star list {path} is not a readable FITS file ({exc})") from None
    found = "; ".join(f"{hdu.name or 'table'}: {[c.lower() for c in hdu.columns.names]}" for hdu in tables)
    held = f"tables found: {found}" if tables else "the file holds no table (an image is solved by solve_image)"
    raise InvalidInputError(f"star list {path}: no FITS table with x and y positions (X, Y as astrometry.net's "
                            f"xylists, X_IMAGE, Y_IMAGE as SExtractor's, or x, y columns); {held}")


def _table_values(path: Path, hdu, names: list[str], max_rows: int
                  ) -> tuple[list[str], NDArray[np.float64], NDArray[np.bool_]]:
    """Every column of ``hdu`` as float64 (N, K), the first element of a vector column, NaN in a
    column that is not numeric; and which columns are (K,)."""
    n = hdu.data.shape[0] if hdu.data is not None else 0
    if n > max_rows:
        raise InvalidInputError(f"star list {path} has more than {max_rows:,} rows")
    values = np.full((n, len(names)), np.nan)
    numeric = np.array([np.issubdtype(np.dtype(column.dtype).base, np.number) for column in hdu.columns])
    for k in np.flatnonzero(numeric) if n else []:
        values[:, k] = np.asarray(hdu.data.field(k)).reshape(n, -1)[:, 0]
    return names, values, numeric
