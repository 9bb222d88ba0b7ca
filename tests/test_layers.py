"""The layer order of ARCHITECTURE.md §1 holds: every import of every module under src/eyelume
(at the top or inside a function) goes to its own layer or one to its left, and report/ imports
nothing that traces rays."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "eyelume"

#: Rank of each layer (ARCHITECTURE.md §1); a module may import ranks ≤ its own. ``errors`` is
#: the error root every layer raises, ``json_files`` the strict JSON every layer writes;
#: ``kernels`` import nothing from eyelume, so the compiled scene (which packs arrays in the
#: kernels' layout) may import their layout constants.
LAYERS = {
    "errors": 0,
    "json_files": 0,
    "scene": 1,
    "kernels": 1,
    "compile": 2,
    "estimators": 3,
    "info": 3,
    "layout": 3,
    "detectors": 4,
    "analysis": 5,
    "render": 6,
    "optimize": 7,
    "report": 8,
    "cli": 9,
    "__main__": 9,  # `python -m eyelume`: the CLI itself
}

#: report/ reads stored results and draws; it never traces a ray, directly or not.
TRACES_RAYS = ("eyelume.kernels", "eyelume.estimators", "eyelume.render", "eyelume.layout")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "eyelume" or len(parts) == 1:
        return None  # not eyelume, or the package itself (its __init__ is the public facade)
    return parts[1]


def _in_type_checking(node: ast.AST, parents: dict[ast.AST, ast.AST]) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            return True
    return False


def eyelume_imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every eyelume import in the file — top level, in functions, relative
    ones resolved — except those under ``if TYPE_CHECKING:`` (annotations only, never run)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    me = _module_name(path).split(".")
    package = me if path.name == "__init__.py" else me[:-1]
    out = []
    for node in ast.walk(tree):
        if _in_type_checking(node, parents):
            continue
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.startswith("eyelume")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module.startswith("eyelume"):
                # `from eyelume import kernels` imports the subpackage eyelume.kernels
                names = [a.name for a in node.names] if module == "eyelume" else [None]
                out += [(node.lineno, f"{module}.{n}" if n else module) for n in names]
    return out


MODULES = sorted(p for p in PACKAGE.rglob("*.py"))


def test_every_layer_is_ranked():
    layers = {_layer(_module_name(p)) for p in MODULES} - {None}
    assert layers <= set(LAYERS), f"modules in no layer: {sorted(layers - set(LAYERS))}"


def test_the_walk_sees_imports_inside_functions(tmp_path):
    pkg = tmp_path / "eyelume" / "estimators"
    pkg.mkdir(parents=True)
    f = pkg / "x.py"
    f.write_text(
        "def g():\n    from eyelume.analysis.regions import region_masks\n"
        "    from ..kernels import rng\n",
        encoding="utf-8",
    )
    global SRC
    saved, SRC = SRC, tmp_path
    try:
        assert [m for _, m in eyelume_imports(f)] == ["eyelume.analysis.regions", "eyelume.kernels"]
    finally:
        SRC = saved


@pytest.mark.parametrize("path", MODULES, ids=lambda p: _module_name(p))
def test_no_import_against_the_layer_order(path):
    me = _module_name(path)
    mine = _layer(me)
    if mine is None:
        return
    against = [
        f"line {line}: {module} ({_layer(module)})"
        for line, module in eyelume_imports(path)
        if _layer(module) is not None and LAYERS[_layer(module)] > LAYERS[mine]
    ]
    assert not against, f"{me} ({mine}) imports from layers to its right: {against}"


def test_report_imports_nothing_that_traces_rays():
    report = sorted((PACKAGE / "report").rglob("*.py"))
    assert report
    direct = [
        f"{_module_name(p)} line {line}: {m}"
        for p in report
        for line, m in eyelume_imports(p)
        if m.startswith(TRACES_RAYS) or m == "eyelume"
    ]
    assert not direct, direct
    # nor indirectly: importing every report module loads no tracing module
    names = ", ".join(_module_name(p) for p in report)
    code = (
        f"import sys, importlib\nfor n in '{names}'.split(', '):\n    importlib.import_module(n)\n"
        f"print('\\n'.join(m for m in sys.modules if m.startswith({TRACES_RAYS!r})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    assert out.stdout.strip() == "", f"report/ loads: {out.stdout.split()}"
