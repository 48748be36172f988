"""The order in which lost-in-space matchers pick sets of image stars (Huffman 2006 §5.5.2).

Mortari's Pyramid order for triads, ``(i, i + dj, i + dj + dk)`` with the gaps in the outer loops
and the first star in the inner one, generalised to sets of any size: the gaps between
consecutive members run in nested loops (first gap outermost), the first member innermost. The
stars change as fast as possible between successive sets, so one missing or false bright star does
not stall the search, and the brightest stars still come first.
"""

from __future__ import annotations

from collections.abc import Iterator

from ..errors import InvalidInputError


def ordered_star_sets(size: int, n: int) -> Iterator[tuple[int, ...]]:
    """Every ``size``-subset of ``n`` stars (0 = brightest), each once, in the generalised Pyramid order.

    For ``size == 3`` this is :func:`.pyramid.pyramid_triads`; for ``size == 2`` it is
    ``(0, 1), (1, 2), ..., (0, 2), (1, 3), ...``.

    Parameters
    ----------
    size : int
        Stars per set, at least 1.
    n : int
        Stars to choose from.
    """
    if size < 1:
        raise InvalidInputError(f"size must be a positive number of stars per set, got {size}")
    yield from _sets(size - 1, (), n)


def _sets(gaps_left: int, gaps: tuple[int, ...], n: int) -> Iterator[tuple[int, ...]]:
    """Sets whose first gaps are ``gaps``, with ``gaps_left`` more gaps to choose (each at least 1)."""
    span = sum(gaps)
    if gaps_left == 0:
        for i in range(n - span):
            offsets = [0]
            for gap in gaps:
                offsets.append(offsets[-1] + gap)
            yield tuple(i + o for o in offsets)
        return
    for gap in range(1, n - span - gaps_left + 1):
        yield from _sets(gaps_left - 1, (*gaps, gap), n)


def further_stars(chosen: tuple[int, ...], n: int) -> list[int]:
    """The stars among the ``n`` brightest not in ``chosen``, brightest first (pivot candidates)."""
    taken = set(chosen)
    return [i for i in range(n) if i not in taken]
