"""One-off refactor (issue 21 item 1), run on a checkout: python publicize.py ROOT

1. Every module of a subpackage gets a leading underscore (the package's __init__ is the contract).
2. Lazy __init__ files list their names as imports under ``if TYPE_CHECKING:`` (mypy sees the
   real types); at run time ``_EXPORTS`` is read from that block by ``startrack._exports_of``.
3. Imports in src/startrack of another subpackage's module are routed through the nearest
   package that exports all the imported names.
4. Dotted names and paths of the renamed modules are rewritten everywhere (py, md, toml).

Status (2026-12-02): not applied yet. Tried on a worktree of b0bb449: 303 modules renamed, then
``ruff check --fix --select I`` sorts the imports; left were 416 F401 findings (the
TYPE_CHECKING imports of the __init__ files: needs ``[tool.ruff.lint.per-file-ignores]
"__init__.py" = ["F401"]`` or ``import x as x`` re-exports) and one E402; mypy, the suite and
tests/test_public_api.py's IMPORTS_PAST_INIT list (to regenerate with reasons) were not run.
Strings naming modules relatively (identify/registry.py ``_load``, attitude/wahba.py's
deferred imports) and ``catalog.cone``-style attribute access in tests need a look by hand.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(sys.argv[1]).resolve()
SRC = ROOT / "src"
PKG = SRC / "startrack"


def dotted(path: Path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def is_package(name: str) -> bool:
    return SRC.joinpath(*name.split("."), "__init__.py").is_file()


PACKAGES = sorted(dotted(p) for p in PKG.rglob("__init__.py"))
RENAME: dict[str, str] = {}
for package in PACKAGES:
    if package == "startrack":
        continue
    folder = SRC.joinpath(*package.split("."))
    for path in sorted(folder.glob("*.py")):
        if path.name.startswith("_"):
            continue
        assert not (folder / f"_{path.name}").exists(), path
        RENAME[f"{package}.{path.stem}"] = f"{package}._{path.stem}"


def renamed(module: str) -> str:
    """``module`` after the renames (a module or anything inside it)."""
    parts = module.split(".")
    for i in range(len(parts), 1, -1):
        head = ".".join(parts[:i])
        if head in RENAME:
            return ".".join([RENAME[head], *parts[i:]])
    return module


def literal_exports(init: Path) -> dict[str, str] | None:
    tree = ast.parse(init.read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", None) == "_EXPORTS":
            return ast.literal_eval(node.value)
    return None


def eager_exports(init: Path) -> dict[str, str]:
    tree = ast.parse(init.read_text())
    found = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            for alias in node.names:
                found[alias.asname or alias.name] = "." + node.module
    return found


# package -> {name: absolute defining module (old name)}
EXPORTS: dict[str, dict[str, str]] = {}
LAZY: dict[str, dict[str, str]] = {}
for package in PACKAGES:
    init = SRC.joinpath(*package.split("."), "__init__.py")
    lazy = literal_exports(init)
    relative = lazy if lazy is not None else eager_exports(init)
    if lazy is not None:
        LAZY[package] = lazy
    EXPORTS[package] = {name: package + origin for name, origin in relative.items()}


def absolute(node: ast.ImportFrom, module_name: str, is_init: bool) -> str:
    if not node.level:
        return node.module or ""
    package = module_name if is_init else module_name.rpartition(".")[0]
    head = package.split(".")[: package.count(".") + 2 - node.level]
    return ".".join(head + ([node.module] if node.module else []))


def relative_text(target: str, module_name: str, is_init: bool, level: int) -> str:
    package = module_name if is_init else module_name.rpartition(".")[0]
    head = ".".join(package.split(".")[: package.count(".") + 2 - level])
    assert target == head or target.startswith(head + "."), (target, module_name, level)
    return "." * level + target[len(head) + 1:]


def route(importer: str, target: str, names: list[str]) -> str | None:
    """The nearest package above ``target`` (outside the importer's own subpackage) exporting all names."""
    top = ".".join(importer.split(".")[:2])
    parts = target.split(".")
    for i in range(len(parts) - 1, 1, -1):
        package = ".".join(parts[:i])
        if importer == package or importer.startswith(package + ".") or top == ".".join(parts[:2]):
            return None
        if is_package(package) and all(n in EXPORTS.get(package, {}) for n in names):
            return package
    return None


def alias_text(alias: ast.alias) -> str:
    return alias.name + (f" as {alias.asname}" if alias.asname else "")


def rewrite_imports(path: Path, in_src: bool) -> str:
    text = path.read_text()
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return text
    module_name = dotted(path) if in_src else "tests.x"
    is_init = path.name == "__init__.py"
    lines = text.splitlines(keepends=True)
    edits = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level and not in_src:
            continue
        target = absolute(node, module_name, is_init)
        if not target.startswith("startrack"):
            continue
        names = [a.name for a in node.names]
        new_aliases = []
        for alias in node.names:
            full = f"{target}.{alias.name}"
            if full in RENAME:  # a module imported from its package
                new_aliases.append(f"{RENAME[full].rpartition('.')[2]} as {alias.asname or alias.name}")
            else:
                new_aliases.append(alias_text(alias))
        new_target = renamed(target)
        via = route(module_name, target, names) if in_src and not is_package(target) else None
        if via is not None:
            new_module = via
        elif node.level:
            new_module = relative_text(new_target, module_name, is_init, node.level)
        else:
            new_module = new_target
        old_module = "." * node.level + (node.module or "") if node.level else node.module
        if new_module == old_module and new_aliases == [alias_text(a) for a in node.names]:
            continue
        segment = "".join(lines[node.lineno - 1: node.end_lineno])
        if "#" in ast.get_source_segment(text, node):
            if new_aliases != [alias_text(a) for a in node.names]:
                raise SystemExit(f"{path}:{node.lineno}: comment inside a module-alias import")
            pattern = rf"from\s+{re.escape(old_module)}\s+import"
            new_segment, n = re.subn(pattern, f"from {new_module} import", segment, count=1)
            assert n == 1, (path, node.lineno)
        else:
            indent = " " * node.col_offset
            prefix = lines[node.lineno - 1][: node.col_offset]
            suffix = lines[node.end_lineno - 1][node.end_col_offset:]
            new_segment = f"{prefix}from {new_module} import {', '.join(new_aliases)}{suffix}"
            assert prefix.strip() == "" or prefix.strip().endswith(":"), (path, node.lineno)
            del indent
        edits.append((node.lineno, node.end_lineno, new_segment))
    for start, end, segment in sorted(edits, reverse=True):
        lines[start - 1: end] = [segment]
    return "".join(lines)


INIT_BLOCK = '''if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
{imports}

_EXPORTS = _exports_of(__file__)
'''


def rewrite_lazy_init(package: str) -> None:
    init = SRC.joinpath(*package.split("."), "__init__.py")
    text = init.read_text()
    tree = ast.parse(text)
    node = next(n for n in tree.body if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", None) == "_EXPORTS")
    by_module: dict[str, list[str]] = {}
    for name, origin in LAZY[package].items():
        new = renamed(package + origin)
        by_module.setdefault(relative_text(new, package, True, 1), []).append(name)
    imports = "\n".join(f"    from {module} import {', '.join(sorted(names))}" for module, names in sorted(by_module.items()))
    lines = text.splitlines(keepends=True)
    lines[node.lineno - 1: node.end_lineno] = [INIT_BLOCK.format(imports=imports)]
    text = "".join(lines)
    if package == "startrack":
        text = text.replace("\n_EXPORTS = _exports_of(__file__)\n", "\n_EXPORTS = _exports_of(__file__)\n", 1)
    else:
        text = text.replace("from .. import _lazy_exports", "from .. import _exports_of, _lazy_exports", 1)
        text = text.replace("from ... import _lazy_exports", "from ... import _exports_of, _lazy_exports", 1)
        text = text.replace("from .... import _lazy_exports", "from .... import _exports_of, _lazy_exports", 1)
    if "TYPE_CHECKING" not in text.split("if TYPE_CHECKING:")[0]:
        text = text.replace("from __future__ import annotations\n", "from __future__ import annotations\n\nfrom typing import TYPE_CHECKING\n", 1)
    init.write_text(text)


def rewrite_names(text: str, path: Path) -> str:
    for old in sorted(RENAME, key=len, reverse=True):
        new = RENAME[old]
        text = re.sub(rf"(?<![\w.]){re.escape(old)}(?![\w])", new, text)
        old_path, new_path = old.replace(".", "/") + ".py", new.replace(".", "/") + ".py"
        text = re.sub(rf"(?<![\w]){re.escape(old_path)}", new_path, text)
    if path.suffix == ".py" and path.is_relative_to(PKG):
        package = dotted(path) if path.name == "__init__.py" else dotted(path).rpartition(".")[0]
        for old, new in RENAME.items():
            if old.rpartition(".")[0] == package:
                stem = old.rpartition(".")[2]
                text = re.sub(rf":mod:`(~?)\.{stem}`", rf":mod:`\1._{stem}`", text)
    return text


EXPORTS_OF = '''
def _exports_of(init_file: str) -> dict[str, str]:
    """Public name -> defining module of a lazy package, read from its ``__init__.py``.

    A lazy package lists its names once, as the imports of its ``if TYPE_CHECKING:`` block (what
    mypy and a reader see); at run time nothing there is imported, and this map tells
    :func:`_lazy_exports` which module to load for a name.

    Parameters
    ----------
    init_file : str
        The package's ``__file__``.

    Returns
    -------
    dict of str to str
        Name -> the module relative to the package (``"._solve"``), in the block's order.
    """
    with open(init_file, encoding="utf-8") as file:
        tree = ast.parse(file.read(), init_file)
    exports = {}
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for statement in node.body:
                if isinstance(statement, ast.ImportFrom) and statement.level == 1:
                    module = "." + (statement.module or "")
                    exports.update({alias.asname or alias.name: module for alias in statement.names})
    return exports


'''


def add_exports_of() -> None:
    """Put ``_exports_of`` (the runtime reader of the TYPE_CHECKING block) into startrack/__init__.py."""
    init = PKG / "__init__.py"
    text = init.read_text()
    if "def _exports_of" not in text:
        text = text.replace("import importlib\n", "import ast\nimport importlib\n", 1)
        text = text.replace("def _submodule(", EXPORTS_OF.lstrip("\n") + "def _submodule(", 1)
        init.write_text(text)


def main() -> None:
    add_exports_of()
    files = [p for d in ("src", "tests", "benchmarks", "scripts") for p in (ROOT / d).rglob("*.py")
             if ".venv" not in p.parts]
    for path in files:
        new = rewrite_imports(path, path.is_relative_to(PKG))
        path.write_text(new)
    for package in LAZY:
        rewrite_lazy_init(package)
    texts = [p for d in ("src", "tests", "benchmarks", "scripts", "docs") for p in (ROOT / d).rglob("*")
             if p.is_file() and p.suffix in {".py", ".md", ".toml", ".txt", ".json", ".cfg", ".html", ".js"}
             and ".venv" not in p.parts]
    texts += [ROOT / "README.md", ROOT / "pyproject.toml", ROOT / "tasks.py"]
    for path in texts:
        old = path.read_text()
        new = rewrite_names(old, path)
        if new != old:
            path.write_text(new)
    for old, new in RENAME.items():
        src = SRC.joinpath(*old.split(".")).with_suffix(".py")
        dst = SRC.joinpath(*new.split(".")).with_suffix(".py")
        subprocess.run(["git", "mv", str(src), str(dst)], cwd=ROOT, check=True)
    print(f"{len(RENAME)} modules renamed")


main()
