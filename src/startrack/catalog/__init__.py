"""Hipparcos-2 star catalog: loading, epoch propagation, magnitude filter, double stars, uniform
thinning and cone search (DESIGN.md §2; Huffman 2006 §5.5.4, Jacobs 1995 §5.2)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._chord import angle_from_chord, chord_from_angle
    from ._cone import ConeIndex, cone_search, query_cone
    from ._constellations import constellation_of
    from ._doubles import flag_doubles, merge_doubles
    from ._epoch import EPOCH_RANGE_JYEAR, epoch_jyear, jyear_tdb
    from ._hipparcos import catalog_identity, load_catalog
    from ._star_catalog import StarCatalog
    from ._thinning import fibonacci_sphere, thin_uniform

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
