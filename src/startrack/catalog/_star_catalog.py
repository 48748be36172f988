"""The star catalog as a frozen dataclass of (N,) arrays (DESIGN.md §3, Sky frame and time)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..frames import radec_to_vector
from ._epoch import epoch_jyear as checked_jyear
from ._propagation import propagate_state, propagate_vectors

if TYPE_CHECKING:
    from astropy.time import Time

_BANDS = ("v", "hp")
_FLOAT_FIELDS = ("ra_rad", "dec_rad", "pm_ra_mas_yr", "pm_dec_mas_yr", "parallax_mas", "hp_mag",
                 "b_v", "v_mag")


def _frozen(values: ArrayLike, dtype, name: str) -> NDArray:
    """A read-only 1-D view of ``values`` (the caller's own array stays writable)."""
    arr = np.asarray(values, dtype=dtype)
    if arr.ndim != 1:
        raise InvalidInputError(f"{name} must be a 1-D array of shape (N,), got shape {arr.shape}")
    view = arr.view()
    view.flags.writeable = False
    return view


@dataclass(frozen=True, eq=False)
class StarCatalog:
    """Stars as parallel read-only arrays of shape (N,), positions ICRS at ``epoch_jyear``.

    Attributes
    ----------
    hip : int64 Hipparcos numbers (after :func:`merge_doubles`, the brighter member's).
    ra_rad, dec_rad : ICRS right ascension and declination (radians) at ``epoch_jyear``.
    pm_ra_mas_yr, pm_dec_mas_yr : proper motion ``mu_alpha* = mu_alpha cos(dec)`` and ``mu_delta``.
    parallax_mas : trigonometric parallax (may be <= 0 for distant stars; not used for directions
        unless ``pm_radial_mas_yr`` is non-zero).
    hp_mag : Hipparcos Hp magnitude. b_v : Johnson B-V, NaN when the catalog has none.
    v_mag : estimated Johnson V (:func:`startrack.catalog._photometry.v_from_hp`).
    variable : bool, known variable (:func:`startrack.catalog._photometry.variability_flag`).
    epoch_jyear : Julian year (TDB) of the positions; 1991.25 for Hipparcos.
    pm_radial_mas_yr : radial proper motion ``v_r * parallax / A`` (mas/yr); zeros for the raw
        catalog (no radial velocities), non-zero only after propagation
        (:mod:`startrack.catalog._propagation`).
    """

    hip: NDArray[np.int64]
    ra_rad: NDArray[np.float64]
    dec_rad: NDArray[np.float64]
    pm_ra_mas_yr: NDArray[np.float64]
    pm_dec_mas_yr: NDArray[np.float64]
    parallax_mas: NDArray[np.float64]
    hp_mag: NDArray[np.float64]
    b_v: NDArray[np.float64]
    v_mag: NDArray[np.float64]
    variable: NDArray[np.bool_]
    epoch_jyear: float
    # None means zeros; __post_init__ fills it, so it is always an array once built.
    pm_radial_mas_yr: NDArray[np.float64] = field(default=None)  # type: ignore[arg-type]

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "hip", _frozen(self.hip, np.int64, "hip"))
        for name in _FLOAT_FIELDS:
            set_(self, name, _frozen(getattr(self, name), np.float64, name))
        set_(self, "variable", _frozen(self.variable, bool, "variable"))
        radial = np.zeros(len(self.hip)) if self.pm_radial_mas_yr is None else self.pm_radial_mas_yr
        set_(self, "pm_radial_mas_yr", _frozen(radial, np.float64, "pm_radial_mas_yr"))
        set_(self, "epoch_jyear", checked_jyear(self.epoch_jyear, "epoch_jyear"))
        n = len(self.hip)
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray) and len(value) != n:
                raise InvalidInputError(
                    f"{f.name} has {len(value)} entries but hip has {n}; all arrays must be (N,)"
                )

    @classmethod
    def from_positions(cls, ra_rad: ArrayLike, dec_rad: ArrayLike, v_mag: ArrayLike, *,
                       epoch_jyear: float = 2000.0, hip: ArrayLike | None = None) -> StarCatalog:
        """A synthetic catalog (N,) of fixed stars: no proper motion or parallax, Hp = V,
        no colour, not variable; ``hip`` defaults to 1..N. For tests and simulations."""
        ra = np.asarray(ra_rad, dtype=float)
        dec, v = np.broadcast_to(dec_rad, ra.shape), np.broadcast_to(v_mag, ra.shape)
        zeros = np.zeros(ra.shape)
        hip = np.arange(1, ra.size + 1) if hip is None else np.asarray(hip)
        return cls(hip=hip, ra_rad=ra, dec_rad=dec, pm_ra_mas_yr=zeros, pm_dec_mas_yr=zeros,
                   parallax_mas=zeros, hp_mag=v, b_v=np.full(ra.shape, np.nan), v_mag=v,
                   variable=np.zeros(ra.shape, dtype=bool), epoch_jyear=epoch_jyear)

    def __len__(self) -> int:
        return len(self.hip)

    def _arrays(self) -> dict[str, NDArray]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != "epoch_jyear"}

    def take(self, index: ArrayLike | slice) -> StarCatalog:
        """A new catalog of the selected stars: integer indices, a boolean mask (N,) or a slice."""
        if not isinstance(index, slice):
            index = np.asarray(index)
            if index.dtype == bool and index.shape != (len(self),):
                raise InvalidInputError(
                    f"a boolean index must have shape ({len(self)},), got {index.shape}"
                )
            if index.dtype != bool and not np.issubdtype(index.dtype, np.integer):
                if index.size:
                    raise InvalidInputError(
                        f"index must be integers or booleans, got {index.dtype}")
                index = index.astype(np.int64)
        arrays = {name: arr[index] for name, arr in self._arrays().items()}
        return StarCatalog(**arrays, epoch_jyear=self.epoch_jyear)

    def magnitudes(self, band: str = "v") -> NDArray[np.float64]:
        """Magnitudes (N,) in ``band``: "v" (estimated Johnson V) or "hp" (Hipparcos Hp)."""
        if not (isinstance(band, str) and band in _BANDS):
            raise InvalidInputError(f"band must be one of {_BANDS}, got {band!r}")
        return self.v_mag if band == "v" else self.hp_mag

    def brighter_than(self, max_mag: float, band: str = "v") -> StarCatalog:
        """The stars with magnitude <= ``max_mag`` in ``band`` ("v" or "hp")."""
        return self.take(self.magnitudes(band) <= float(max_mag))

    def vectors(self, epoch_jyear: float | Time | None = None) -> NDArray[np.float64]:
        """ICRS unit vectors (N, 3); moved by space motion to ``epoch_jyear`` when given.

        ``epoch_jyear`` is a Julian year (TDB) or an astropy ``Time``; None means the catalog's own
        epoch. Model: :mod:`startrack.catalog._propagation`.
        """
        if epoch_jyear is None:
            return radec_to_vector(self.ra_rad, self.dec_rad)
        dt = checked_jyear(epoch_jyear, "epoch_jyear") - self.epoch_jyear
        if dt == 0.0:
            return radec_to_vector(self.ra_rad, self.dec_rad)
        return propagate_vectors(self.ra_rad, self.dec_rad, self.pm_ra_mas_yr,
                                 self.pm_dec_mas_yr, self.pm_radial_mas_yr, dt)

    def propagated(self, epoch_jyear: float | Time) -> StarCatalog:
        """A new catalog whose positions, proper motions and parallaxes are at ``epoch_jyear``."""
        epoch = checked_jyear(epoch_jyear, "epoch_jyear")
        state = propagate_state(self.ra_rad, self.dec_rad, self.pm_ra_mas_yr, self.pm_dec_mas_yr,
                                self.pm_radial_mas_yr, epoch - self.epoch_jyear)
        return dataclasses.replace(
            self, ra_rad=state.ra_rad, dec_rad=state.dec_rad, pm_ra_mas_yr=state.pm_ra_mas_yr,
            pm_dec_mas_yr=state.pm_dec_mas_yr, pm_radial_mas_yr=state.pm_radial_mas_yr,
            parallax_mas=self.parallax_mas / state.distance_scale, epoch_jyear=epoch,
        )
