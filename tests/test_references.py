"""Citations anyone can resolve (issue 21 item 5): every "Author YYYY" key that ``src/`` and
``docs/`` cite is listed in docs/references.md, and none cites a seed by number ("seed 000 §5.4")
or a notes file ("notes seed-000.md §1.16") any more; nor does any .py, .toml or .html file of
``src/``, any page of ``docs/`` or README.md, code, spec names and program output included
(:func:`test_no_document_is_cited_by_seed_number`).

The files checked are a parameter (:func:`checked_files`); :data:`NOT_YET_REWRITTEN` (empty now
that every file is rewritten) names any left out, with the reason beside it.
"""

from __future__ import annotations

import functools
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
REFERENCES = ROOT / "docs" / "references.md"

NOT_YET_REWRITTEN: tuple[str, ...] = ()

NOT_CITATIONS = {"September 2013"}
"""Author-year look-alikes that are not citations (a date in docs/seed_tables_sease_samaan.md)."""

AUTHOR = r"(?:van |de )?[A-Z][A-Za-z\-]+"
CITATION = re.compile(rf"(?P<first>{AUTHOR})(?:(?:,\s+{AUTHOR})*,?\s+(?:&|and)\s+{AUTHOR}|\s+et\s+al\.)?,?\s+"
                      r"\(?(?P<year>1[6-9]\d\d|20[0-2]\d)[a-z]?\b")
SEED_NUMBER = re.compile(r"\b[Ss]eeds? \d{3}\b|\bseed-\d{3}(?:-\d{3})?(?:\.md)?\b")


def checked_files(skip: tuple[str, ...] = NOT_YET_REWRITTEN) -> list[Path]:
    """The .py files of src/ and the .md pages of docs/ (not references.md, which defines the keys),
    without those whose path starts with ``skip``."""
    files = sorted((ROOT / "src").rglob("*.py")) + sorted((ROOT / "docs").glob("*.md"))
    return [f for f in files if not str(f.relative_to(ROOT)).startswith(skip) and f != REFERENCES]


def prose(path: Path) -> str:
    """The text a citation can sit in: comments and string statements (docstrings) of a .py file,
    the prose of a .md page without its fenced blocks (program output, spec examples)."""
    text = path.read_text()
    if path.suffix == ".md":
        return re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    kept = []
    for i, tok in enumerate(tokens):
        before = next((t for t in reversed(tokens[:i]) if t.type not in (tokenize.NL, tokenize.COMMENT)), None)
        statement = before is None or before.type in (tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT)
        if tok.type == tokenize.COMMENT or (tok.type == tokenize.STRING and statement):
            kept.append(tok.string)
    return "\n".join(kept)


@functools.cache
def defined_keys() -> frozenset[str]:
    """The bold keys that open the entries of docs/references.md ("- **Huffman 2006**: ...")."""
    return frozenset(re.findall(r"^- \*\*(.+?)\*\*", REFERENCES.read_text(), flags=re.M))


def used_keys(text: str) -> set[str]:
    """'First-author year' of every author-year citation in ``text`` (Cole & Crassidis 2006 -> Cole 2006)."""
    return {f"{m['first']} {m['year']}" for m in CITATION.finditer(text)}


def is_defined(key: str) -> bool:
    """A key of the references, or the end of one ("Conventions 2010" of "IERS Conventions 2010")."""
    return key in NOT_CITATIONS or any(k == key or k.endswith(" " + key) for k in defined_keys())


FILES = checked_files()


def test_the_checked_files_are_the_package_and_the_docs():
    names = {str(f.relative_to(ROOT)) for f in FILES}
    assert {"src/startrack/camera.py", "src/startrack/plotting.py", "docs/simulation.md"} <= names
    assert len(FILES) > 200


def test_references_define_the_seed_keys():
    assert {"Huffman 2006", "Sease 2013", "Jacobs 1995", "Fowler 2013", "Samaan 2002"} <= defined_keys()


def test_citation_finder_takes_the_first_author():
    text = "(Cole & Crassidis 2006; Mortari, Markley and Singla 2007; Leinert et al. 1998; van Leeuwen 2007)"
    assert used_keys(text) == {"Cole 2006", "Mortari 2007", "Leinert 1998", "van Leeuwen 2007"}
    assert SEED_NUMBER.search("as seed 000 §5.4 says") and SEED_NUMBER.search("notes ``seed-001-004.md`` §2")
    assert not SEED_NUMBER.search("the spec seed000-table5.1 and SEED000_EQ34")


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_cited_key_is_in_the_references(path):
    text = prose(path)
    unknown = sorted(k for k in used_keys(text) if not is_defined(k))
    assert not unknown, f"cited in {path.name} but not in docs/references.md: {unknown}"
    left = sorted({m.group(0) for m in SEED_NUMBER.finditer(text)})
    assert not left, f"{path.name} still cites seeds by number or notes file: {left}"


SEED_CITATION = re.compile(r"\bseeds?[ -]?0\d\d\b", re.I)
"""A document cited by its old seed number: "seed 000", "Seed 003's", the spec name "seed000-table4.2",
the notes file "seed-001-004.md". Not a random-number seed ("seed=42", "--seed 3", "seed 4003", "seeded")
nor an identifier that still carries the number inside a word ("SEED000_EQ34", "jacobs1995_brightness")."""


def seed_cited_files() -> list[Path]:
    """Every .py, .toml and .html source file of src/, every page of docs/ and README.md."""
    src = [f for f in sorted((ROOT / "src").rglob("*")) if f.suffix in (".py", ".toml", ".html")]
    return src + sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]


def test_seed_citation_finder():
    for cited in ("as seed 000 §5.4 says", "Seed 003's analyses", "run seed000-table4.2-ws-vs-mle",
                  "notes seed-001-004.md §3.5", "the seeds 001 and 002"):
        assert SEED_CITATION.search(cited), cited
    for not_cited in ("rng(seed=42)", "--seed 3", "campaign seed 4003", "seeded with 0", "SEED000_EQ34",
                      "jacobs1995_brightness", "seed 1, 14 frames"):
        assert not SEED_CITATION.search(not_cited), not_cited


def test_no_document_is_cited_by_seed_number():
    files = seed_cited_files()
    assert {ROOT / "README.md", ROOT / "src/startrack/camera.py"} <= set(files)
    assert any(f.suffix == ".toml" for f in files) and len(files) > 200
    left = [f"{f.relative_to(ROOT)}:{n}: {m.group(0)}" for f in files
            for n, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1)
            for m in SEED_CITATION.finditer(line)]
    assert not left, "cite the source by its key in docs/references.md, not by seed number:\n" + "\n".join(left)
