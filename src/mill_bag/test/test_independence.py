"""mill_bag knows nothing of mill: no mill package but mill_common's generic node helpers, its
ROS-free codec (the nodes' CDR reader, which the bag's JointState reader is) and time base (a
stamp in ns), and no mill topic name in its code."""

from __future__ import annotations

import ast
from pathlib import Path

import mill_bag

ALLOWED = {
    'mill_common.codec',
    'mill_common.declared',
    'mill_common.executable',
    'mill_common.node_main',
    'mill_common.parameters',
    'mill_common.timebase',
    'mill_common.ros_params',
    'mill_common.one_line_parser',
    'mill_common.yaml_files',
}
MODULES = sorted(Path(mill_bag.__file__).parent.glob('*.py'))


def imported(tree: ast.AST) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out.add(node.module)
    return out


def docstrings(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                ids.add(id(body[0].value))
    return ids


def test_mill_bag_imports_no_mill_package_but_the_generic_helpers() -> None:
    assert len(MODULES) >= 9
    for path in MODULES:
        mill = {
            m
            for m in imported(ast.parse(path.read_text()))
            if m.startswith('mill_') and not m.startswith('mill_bag')
        }
        assert mill <= ALLOWED, (path.name, mill - ALLOWED)


def test_mill_bag_code_names_no_mill_topic() -> None:
    for path in MODULES:
        tree = ast.parse(path.read_text())
        skip = docstrings(tree)
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and id(node) not in skip
            ):
                assert '/mill' not in node.value, (path.name, node.value)
