"""Two rules of the code base checked on every run: no module of the package is over 600 lines, and the tests use
only public names of hapmotion (no ``from hapmotion.x import _name``, no ``hapmotion.x._module``)."""

from __future__ import annotations

import ast
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
