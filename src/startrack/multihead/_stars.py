"""The star lists of a rig's heads, checked against the rig.

:func:`rig_stars` turns the mapping a caller gives :func:`startrack.solve_rig` (head name to
``(x, y)`` or ``(x, y, flux)`` arrays, our pixel convention) into one :class:`HeadStars` per head,
brightest first, refusing a list for a head the rig does not have, a list for a split detector
(its spots must be classified from the image first), or a malformed list, always naming the head.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..rig import CameraRig, RigHead
from ..solve import _star_arrays


@dataclass(frozen=True)
class HeadStars:
    """One head's stars, brightest first.

    Attributes
    ----------
    head : RigHead
    x, y : ndarray, shape (N,)
        Centroids (px, our convention).
    index : ndarray of int, shape (N,)
        What each star is called in the result's ``det_index``: its row in the caller's list, or
        its detection index on a split detector.
    vectors : ndarray, shape (N, 3)
        Camera-frame unit vectors of the stars.
    """

    head: RigHead
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    index: NDArray[np.int64]
    vectors: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.x.size)

    @property
    def name(self) -> str:
        return self.head.name

    @classmethod
    def of(cls, head: RigHead, x, y, flux=None, index=None) -> HeadStars:
        """Checked stars of ``head`` (sorted by ``flux`` when given); errors name the head."""
        cam = head.camera
        try:
            xs, ys, order = _star_arrays(x, y, flux, cam.width, cam.height)
        except InvalidInputError as exc:
            raise InvalidInputError(f"head {head.name!r}: {exc}") from None
        ids = order if index is None else np.asarray(index, dtype=np.int64)[order]
        return cls(head, xs, ys, ids.astype(np.int64), cam.pixel_to_vector(xs, ys).reshape(-1, 3))


def _arrays(name: str, value) -> tuple:
    """(x, y, flux or None) from a tuple of two or three arrays."""
    if isinstance(value, np.ndarray) or not isinstance(value, tuple | list) or len(value) not in (2, 3):
        raise InvalidInputError(f"head {name!r}: give its stars as a tuple (x, y) or (x, y, flux) of arrays, "
                                f"got {type(value).__name__}")
    return (value[0], value[1], value[2] if len(value) == 3 else None)


def rig_stars(stars: Mapping[str, tuple], rig: CameraRig) -> dict[str, HeadStars]:
    """Each head's checked stars (module docstring); heads with no list get an empty one.

    Raises
    ------
    InvalidInputError
        A key that is not a head of the rig, a split detector's name, or a malformed list.
    """
    if not isinstance(rig, CameraRig):
        raise InvalidInputError(f"rig must be a CameraRig, got {type(rig).__name__}")
    if not isinstance(stars, Mapping):
        raise InvalidInputError("stars must map head names to (x, y) or (x, y, flux) arrays")
    split = rig.split_detectors()
    for name in stars:
        if name in split and name not in rig:
            fields = ", ".join(h.name for h in split[name])
            raise InvalidInputError(f"{name!r} is the detector of split fields {fields}: "
                                    "give its image (solve_rig_images) or each field's stars under its head name")
        if name not in rig:
            raise InvalidInputError(f"star list for head {name!r}, which is not in the rig (heads: "
                                    f"{', '.join(rig.names)})")
    out = {}
    for head in rig:
        if head.name in stars:
            out[head.name] = HeadStars.of(head, *_arrays(head.name, stars[head.name]))
        else:
            out[head.name] = HeadStars.of(head, np.zeros(0), np.zeros(0))
    return out
