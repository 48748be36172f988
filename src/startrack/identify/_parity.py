"""Image parity: whether an image shows the sky as seen, or its mirror image.

A camera looking at the sky makes an image that no rotation turns into its mirror image, so a
lost-in-space match of the one fails on the other: the four stars of a pattern keep their edge
ratios, but no attitude fits them (:mod:`._quad_matcher`). Mirror images are common among photos:
a telescope's star diagonal flips the field, and so do cameras and programs that flip their
output. astrometry.net tries both parities by default; so does :func:`startrack.solve_image`.

A mirror image has a camera whose :attr:`startrack.camera.Camera.mirrored` is set (pixel x =
cx - fx a): the camera frame stays right-handed and the attitude a rotation. The compiled search,
fit and match helpers take plain cameras; they see a mirrored camera's stars through its mirror
image, on the flipped columns x' = width - 1 - x (:func:`unmirrored`), the same stars seen the same
way. The "quads" matcher searches both parities
in one pass, taking turns one look-up step at a time (:func:`.quad_matcher.match_lost_in_space`),
so a mirror image costs about one more look-up per step rather than a failed search first.

Parities (``parity``)
    "normal" -- the image is not mirrored (the default of :func:`startrack.solve_stars`: a star
    tracker knows its optics); "mirrored" -- it is; "either" -- search both (the default of
    :func:`startrack.solve_image`). A camera whose ``mirrored`` is set fixes "mirrored".
"""

from __future__ import annotations

from dataclasses import replace
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ..errors import InvalidInputError

Parity = Literal["normal", "mirrored", "either"]
"""The image parities a solve can be asked for (module docstring)."""

PARITIES: tuple[Parity, ...] = get_args(Parity)
"""The names of :data:`Parity`, in its order (what an unknown ``parity`` is told to be)."""


def check_parity(parity: object, camera: Camera | None, default: Parity) -> tuple[Parity, Camera | None]:
    """The parity to search and the camera as the matchers take it (never ``mirrored``).

    Parameters
    ----------
    parity : {"normal", "mirrored", "either"} or None
        None: the camera's when one is given, else ``default``.
    camera : Camera or None
    default : Parity

    Raises
    ------
    InvalidInputError
        An unknown parity, or one that contradicts a mirrored camera.
    """
    if parity is not None and not (isinstance(parity, str) and parity in PARITIES):
        raise InvalidInputError(f"parity must be one of {', '.join(map(repr, PARITIES))} or None, got {parity!r}")
    if camera is not None and camera.mirrored:
        if parity not in (None, "mirrored"):
            raise InvalidInputError(f"the camera is mirrored (camera.mirrored is True) but parity is {parity!r}; "
                                    "give parity='mirrored' or None")
        return "mirrored", replace(camera, mirrored=False)
    if parity is None:
        return ("normal" if camera is not None else default), camera
    return parity, camera


def searched_mirrors(parity: Parity) -> tuple[bool, ...]:
    """Which hypotheses a search tries, in order: False for the image as given, True for its mirror."""
    return {"normal": (False,), "mirrored": (True,), "either": (False, True)}[parity]


def unmirrored(camera: Camera, x: NDArray) -> tuple[Camera, NDArray]:
    """The camera and the columns ``x`` (N,) as the plain compiled helpers take them: unchanged
    for a plain camera; for a ``mirrored`` one, its mirror image (a plain camera, the principal
    point flipped) and the flipped columns ``width - 1 - x``: the same stars seen the same way."""
    if not camera.mirrored:
        return camera, x
    return camera.mirror_image(), (camera.width - 1) - np.asarray(x, dtype=np.float64)
