"""Rules of the code base checked on every run: no module of the package is over 600 lines, no module imports one
of a higher layer (the layers of docs/CONTRACTS.md, so no import circles either), and the tests use only public
names of hapmotion (no ``from hapmotion.x import _name``, no ``hapmotion.x._module``)."""

from __future__ import annotations

import ast
import graphlib
import importlib
import importlib.util
import inspect
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "hapmotion"
TESTS = ROOT / "tests"
MAX_MODULE_LINES = 600


def is_private(name: str) -> bool:
    """``_x`` (a private module, function, class or constant), not ``__init__`` / ``__version__``."""
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def is_module(module: str, name: str) -> bool:
    try:
        return inspect.ismodule(getattr(importlib.import_module(module), name, None)) or bool(
            importlib.util.find_spec(f"{module}.{name}"))
    except ImportError:
        return False


def private_uses(path: Path) -> list[str]:
    """Every private hapmotion name a test file imports or reaches through a module: ``line: text``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = []
    modules: set[str] = set()  # local names bound to hapmotion modules
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "hapmotion":
                    if any(is_private(part) for part in alias.name.split(".")):
                        found.append(f"{node.lineno}: import {alias.name}")
                    modules.add((alias.asname or alias.name).split(".")[0])
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "hapmotion":
            if any(is_private(part) for part in node.module.split(".")):
                found.append(f"{node.lineno}: from {node.module} import ...")
                continue
            for alias in node.names:
                if is_private(alias.name):
                    found.append(f"{node.lineno}: from {node.module} import {alias.name}")
                elif is_module(node.module, alias.name):
                    modules.add(alias.asname or alias.name)
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and is_private(node.attr):
            root = node.value
            while isinstance(root, ast.Attribute):
                root = root.value
            if isinstance(root, ast.Name) and root.id in modules:
                found.append(f"{node.lineno}: {ast.unparse(node)}")
    return sorted(set(found), key=lambda s: int(s.split(":")[0]))


def test_no_module_of_the_package_is_over_600_lines():
    sizes = {path.relative_to(ROOT): len(path.read_text(encoding="utf-8").splitlines())
             for path in sorted(PACKAGE.rglob("*.py"))}
    assert len(sizes) > 50  # the package was found
    too_long = [f"{path}: {n} lines" for path, n in sizes.items() if n > MAX_MODULE_LINES]
    assert not too_long, f"modules over {MAX_MODULE_LINES} lines (split them by what they hold):\n" + "\n".join(too_long)


LAYERS = ("errors", "json_scan", "limits", "filesafety", "skeleton", "motion", "motion_files", "body", "track",
          "bhaptics.wearables", "bhaptics.devices", "bhaptics.tick", "layout", "rig", "bhaptics", "renderer", "audio", "track_files", "show",
          "live", "audience", "viewer", "metrics", "cli", "console", "__main__")
"""The package from the ground up (docs/CONTRACTS.md): a module may import its own layer and the ones before it.
The bHaptics device catalogue and the Player's tick are vendor facts under the renderer layout; the rest of
``bhaptics/`` (the Player's messages, ``.tact`` files named after the layout) stands on it."""


def layer_of(module: str) -> str:
    """The entry of :data:`LAYERS` a dotted module name ``hapmotion.x.y`` belongs to (the longest that fits)."""
    rest = module.split(".", 1)[1] if "." in module else ""
    return max((layer for layer in LAYERS if rest == layer or rest.startswith(layer + ".")), key=len, default="")


def imports_of(path: Path) -> list[tuple[int, str]]:
    """``(line, hapmotion.module)`` of every import of the package in a module of it (relative ones resolved)."""
    module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = module.removesuffix(".__init__") if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else []))
            targets = [base] if node.module else [f"{base}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            continue
        out.extend((node.lineno, t) for t in targets if t.split(".")[0] == "hapmotion")
    return out


def test_no_module_imports_a_higher_layer():
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        here = layer_of(".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__"))
        if not here:
            continue  # hapmotion/__init__.py: the lazy public face over everything
        for line, target in imports_of(path):
            there = layer_of(target)
            if there and LAYERS.index(there) > LAYERS.index(here):
                upward.append(f"{path.relative_to(ROOT)}:{line}: {here} imports {target} ({there})")
    assert not upward, "imports from a lower layer to a higher one:\n" + "\n".join(upward)


def test_no_import_circles():
    """No module imports one that (through others) imports it back, within a layer either."""
    modules = {".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__"): p
               for p in PACKAGE.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        deps = set()
        for _, target in imports_of(path):
            while target and target not in modules:  # a name imported from a module: the module
                target = target.rpartition(".")[0]
            if target and target != name:
                deps.add(target)
        graph[name] = deps
    try:
        tuple(graphlib.TopologicalSorter(graph).static_order())
    except graphlib.CycleError as exc:
        pytest.fail(f"an import circle: {' -> '.join(exc.args[1])}")


def test_the_layer_check_sees_an_upward_import(tmp_path, monkeypatch):
    """The check reads relative imports the way Python does: a layout that imports the renderer is caught."""
    fake = tmp_path / "hapmotion"
    fake.mkdir()
    (fake / "layout.py").write_text("from .renderer import Renderer\nfrom .errors import UsageError\n")
    monkeypatch.setattr(__import__(__name__), "PACKAGE", fake)
    assert imports_of(fake / "layout.py") == [(1, "hapmotion.renderer"), (2, "hapmotion.errors")]
    assert layer_of("hapmotion.renderer") == "renderer" and layer_of("hapmotion.bhaptics.sdk1") == "bhaptics"
    assert layer_of("hapmotion.bhaptics.devices") == "bhaptics.devices"
    assert LAYERS.index(layer_of("hapmotion.renderer")) > LAYERS.index(layer_of("hapmotion.layout"))


def test_tests_use_only_public_names_of_the_package():
    files = sorted(TESTS.rglob("*.py"))
    assert len(files) > 50  # the tests were found
    uses = {path.relative_to(ROOT): private_uses(path) for path in files}
    found = [f"{path}:{use}" for path, found in uses.items() for use in found]
    assert not found, "tests importing private names (test the public seam instead):\n" + "\n".join(found)


@pytest.mark.parametrize("source, expected", [
    ("from hapmotion.viewer.plot import _groups, plot_track", ["1: from hapmotion.viewer.plot import _groups"]),
    ("from hapmotion.motion_files._floats import parse_table", ["1: from hapmotion.motion_files._floats import ..."]),
    ("import hapmotion.motion_files._floats as f", ["1: import hapmotion.motion_files._floats"]),
    ("from hapmotion import motion_files\nmotion_files._floats.OK", ["2: motion_files._floats"]),
    ("import hapmotion\nhapmotion.renderer._x\nhapmotion.__version__", ["2: hapmotion.renderer._x"]),
    ("from hapmotion.track import HapticTrack\nimport numpy as np\nnp._x\ntrack._meta", []),
])
def test_private_uses_are_found(tmp_path, source, expected):
    path = tmp_path / "test_x.py"
    path.write_text(source + "\n", encoding="utf-8")
    assert sorted(private_uses(path)) == sorted(expected)
