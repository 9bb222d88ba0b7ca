"""ARCHITECTURE.md stays true: every module and package under src/eyelume is named in its §3
Layout, and every module it names there exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "eyelume"


def _layout() -> str:
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    start = text.index("## 3. Layout")
    end = text.index("\n## ", start + 1)
    return text[start:end]


def _tree_entries(layout: str) -> list[tuple[int, str]]:
    """(indent, name) of each entry of the layout's tree: the first word of each code line."""
    block = layout[layout.index("```") + 3 : layout.rindex("```")]
    out = []
    for line in block.splitlines():
        m = re.match(r"( *)([\w.\-/]+)", line)
        if m and not line.lstrip().startswith("#"):
            out.append((len(m.group(1)), m.group(2)))
    return out


def documented_paths() -> set[str]:
    """Paths under src/eyelume the layout tree names, from its indentation."""
    stack: list[tuple[int, str]] = []
    paths = set()
    for indent, name in _tree_entries(_layout()):
        while stack and stack[-1][0] >= indent:
            stack.pop()
        path = "/".join([s for _, s in stack] + [name]).replace("//", "/")
        if name.endswith("/"):
            stack.append((indent, name.rstrip("/")))
        paths.add(path.rstrip("/"))
    return {p.removeprefix("src/eyelume/") for p in paths if p.startswith("src/eyelume/")}


def existing_paths() -> set[str]:
    out = set()
    for p in PACKAGE.rglob("*.py"):
        rel = p.relative_to(PACKAGE)
        if "__pycache__" in rel.parts:
            continue
        if p.name == "__init__.py":
            if rel.parent != Path("."):
                out.add(rel.parent.as_posix())  # a package: named by its folder
            else:
                out.add("__init__.py")
        else:
            out.add(rel.as_posix())
    return out


def test_every_module_is_named_in_the_layout():
    missing = existing_paths() - documented_paths()
    assert not missing, f"ARCHITECTURE.md §3 lacks: {sorted(missing)}"


def test_every_module_the_layout_names_exists():
    documented = {p for p in documented_paths() if p.endswith(".py") or "." not in p}
    stale = {p for p in documented if not (PACKAGE / p).exists()}
    assert not stale, f"ARCHITECTURE.md §3 names what does not exist: {sorted(stale)}"


def test_the_parser_reads_the_tree():
    paths = documented_paths()
    assert {"errors.py", "scene", "scene/glass.py", "analysis/tracking/gaze.py"} <= paths
