"""Observing sites: latitude, longitude, height and typical weather, saved by name.

Sites are kept in a JSON file in the user's configuration folder: ``$STARTRACK_CONFIG_DIR/sites.json``
when that variable is set, else ``$XDG_CONFIG_HOME/startrack/sites.json`` (``~/.config/startrack``).
A few sites ship with the package (Fowler 2013's, Table 2.1 and B.1); a saved site of the same name
replaces a built-in one.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

from ..errors import InvalidInputError
from ..io import atomic_path

SCALE_HEIGHT_M = 8434.0
"""Pressure scale height of an isothermal atmosphere near 15 C, for the default pressure."""


@dataclass(frozen=True)
class Site:
    """A place on the Earth (WGS84 geodetic).

    Attributes
    ----------
    name : str
    latitude_deg : float
        North positive.
    longitude_deg : float
        East positive (west longitudes are negative).
    height_m : float
        Above the ellipsoid (mean sea level is close enough for refraction and parallax).
    temperature_c : float
        Typical air temperature, for refraction (10 C is Bennett's standard).
    pressure_kpa : float or None
        Air pressure; None means the standard atmosphere at ``height_m``.
    """

    name: str
    latitude_deg: float
    longitude_deg: float
    height_m: float = 0.0
    temperature_c: float = 10.0
    pressure_kpa: float | None = None

    def __post_init__(self) -> None:
        if not self.name or not isinstance(self.name, str):
            raise InvalidInputError(f"a site needs a name, got {self.name!r}")
        if not (math.isfinite(self.latitude_deg) and -90.0 <= self.latitude_deg <= 90.0):
            raise InvalidInputError(f"latitude_deg must be within -90..90, got {self.latitude_deg!r}")
        if not (math.isfinite(self.longitude_deg) and -180.0 <= self.longitude_deg <= 360.0):
            raise InvalidInputError(
                f"longitude_deg must be within -180..360 (east positive), got {self.longitude_deg!r}")
        if not (math.isfinite(self.height_m) and -500.0 <= self.height_m <= 9000.0):
            raise InvalidInputError(f"height_m must be within -500..9000 m, got {self.height_m!r}")

    @property
    def pressure(self) -> float:
        """Air pressure in kPa: the saved one, or 101.325 exp(-height / 8434 m)."""
        if self.pressure_kpa is not None:
            return float(self.pressure_kpa)
        return 101.325 * math.exp(-self.height_m / SCALE_HEIGHT_M)


BUILTIN_SITES: dict[str, Site] = {
    s.name: s for s in (
        Site("logan-ut", 41.742597, -111.842483, 1382.0),
        Site("logan-ut-2012", 41.771948, -111.749832, 1460.0),
        Site("moab-ut", 38.77356, -109.58103, 1300.0),
    )
}
"""Fowler 2013 Table 2.1 / B.1 sites (heights are ours, from the terrain; the thesis gives none)."""


def sites_file() -> Path:
    """Where saved sites live (see the module docstring)."""
    if os.environ.get("STARTRACK_CONFIG_DIR"):
        return Path(os.environ["STARTRACK_CONFIG_DIR"]) / "sites.json"
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "startrack" / "sites.json"


def load_sites() -> dict[str, Site]:
    """Built-in and saved sites by name (saved ones win)."""
    sites = dict(BUILTIN_SITES)
    path = sites_file()
    if path.is_file():
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            sites.update({entry["name"]: Site(**entry) for entry in data.get("sites", [])})
        except (ValueError, TypeError, KeyError) as exc:
            raise InvalidInputError(f"{path} is not a valid sites file: {exc}") from exc
    return sites


def get_site(name: str) -> Site:
    sites = load_sites()
    if name not in sites:
        raise InvalidInputError(f"unknown site {name!r}; known sites: {', '.join(sorted(sites))}")
    return sites[name]


def _write(saved: dict[str, Site]) -> Path:
    path = sites_file()
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({"sites": [asdict(s) for s in saved.values()]}, indent=2))
    return path


def _saved() -> dict[str, Site]:
    return {n: s for n, s in load_sites().items() if BUILTIN_SITES.get(n) != s}


def save_site(site: Site) -> Path:
    """Save (or replace) a site under its name; returns the file written."""
    saved = _saved()
    saved[site.name] = site
    return _write(saved)


def delete_site(name: str) -> Path:
    """Remove a saved site (built-in ones cannot be removed)."""
    saved = _saved()
    if name not in saved:
        raise InvalidInputError(f"no saved site named {name!r}")
    del saved[name]
    return _write(saved)
