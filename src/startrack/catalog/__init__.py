"""Hipparcos-2 star catalog: loading, epoch propagation, magnitude filter, double stars, uniform
thinning and cone search (DESIGN.md §2; seed 000 §5.5.4, seed 002 §5.2)."""

from .cone import ConeIndex, cone_search
from .doubles import flag_doubles, merge_doubles
from .hipparcos import load_catalog
from .propagation import propagate
from .star_catalog import StarCatalog
from .thinning import thin_uniform

__all__ = [
    "ConeIndex",
    "StarCatalog",
    "cone_search",
    "flag_doubles",
    "load_catalog",
    "merge_doubles",
    "propagate",
    "thin_uniform",
]
