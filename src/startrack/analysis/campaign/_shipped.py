"""The specs shipped with the package (``startrack/analysis/campaign/specs/*.toml``), by name.

``startrack campaign list`` lists them; ``startrack campaign run NAME`` runs one. Each spec named
after a source's key (``huffman2006-table4.2-ws-vs-mle``: Huffman 2006 Table 4.2, docs/references.md)
reproduces one reference result of that source and prints ours beside the source's.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ...errors import InvalidInputError

SPECS_DIR = Path(__file__).resolve().parent / "specs"


@dataclass(frozen=True)
class ShippedSpec:
    """A spec file with its name (the file's stem), level and one-line description."""

    name: str
    path: Path
    level: str
    description: str


def list_specs() -> list[ShippedSpec]:
    """The shipped specs, sorted by name."""
    out = []
    for path in sorted(SPECS_DIR.glob("*.toml")):
        head = tomllib.loads(path.read_text(encoding="utf-8")).get("campaign", {})
        text = " ".join(str(head.get("description", "")).split())
        out.append(ShippedSpec(path.stem, path, str(head.get("level", "stars")), text))
    return out


def find_spec(name_or_path: str | Path) -> Path:
    """The spec file for a path, or for the name of a shipped spec.

    Raises
    ------
    InvalidInputError
        When it is neither an existing file nor a shipped spec's name.
    """
    path = Path(name_or_path)
    if path.is_file():
        return path
    shipped = SPECS_DIR / f"{name_or_path}.toml"
    if shipped.is_file():
        return shipped
    names = ", ".join(s.name for s in list_specs()) or "none"
    renamed = ("; the specs named seedNNN-... before are named after their source now, as huffman2006-..., "
               "docs/references.md" if re.match(r"seed\d{3}-", str(name_or_path)) else "")
    raise InvalidInputError(f"no spec file {str(name_or_path)!r} and no shipped spec of that name "
                            f"(shipped: {names}; see 'startrack campaign list'{renamed})")
