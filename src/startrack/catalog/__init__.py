"""Hipparcos-2 star catalog: loading, epoch propagation, magnitude filter, double stars, uniform
thinning and cone search (DESIGN.md §2; Huffman 2006 §5.5.4, Jacobs 1995 §5.2)."""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "angle_from_chord": ".chord",
    "chord_from_angle": ".chord",
    "ConeIndex": ".cone",
    "EPOCH_RANGE_JYEAR": ".epoch",
    "epoch_jyear": ".epoch",
    "cone_search": ".cone",
    "flag_doubles": ".doubles",
    "merge_doubles": ".doubles",
    "jyear_tdb": ".epoch",
    "load_catalog": ".hipparcos",
    "query_cone": ".cone",
    "StarCatalog": ".star_catalog",
    "fibonacci_sphere": ".thinning",
    "thin_uniform": ".thinning",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
