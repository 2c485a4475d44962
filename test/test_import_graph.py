"""The package layering of mill, checked on the source (ast only: nothing is imported).

Every Python file under src/<package>/ except tests and setup.py is parsed, and every
``import`` / ``from ... import`` in it is collected, at module level or inside functions,
absolute or relative. The rules:

1. The role packages (mill_plant, mill_controllers, mill_observers, mill_trajectory) never
   import one another: what more than one of them needs lives in mill_models.
2. mill_models is ROS-free: its modules, and the mill_common modules they reach, import only
   the standard library, numpy and scipy, and of the mill packages only mill_models and
   mill_common's ROS-free modules (signals, parameters, timebase).
3. No package has an import cycle among its own modules.
4. mill_analysis (records, reports, the papers' verdicts) reads messages and bags only: it
   imports neither mill_bringup, mill_bench nor any role package.
5. mill_bringup does not import mill_bench; no package does (the benchmark is a leaf).
6. No import cycle between packages.

Dynamic imports (importlib.import_module) are not seen.
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / 'src'
ROLE_PACKAGES = ('mill_plant', 'mill_controllers', 'mill_observers', 'mill_trajectory')
MODELS = 'mill_models'
ROS_FREE_COMMON = (
    'mill_common.signals',
    'mill_common.parameters',
    'mill_common.declared',
    'mill_common.timebase',
)
MODELS_MAY_USE = ('numpy', 'scipy')
ANALYSIS, BRINGUP, BENCH = 'mill_analysis', 'mill_bringup', 'mill_bench'


@dataclass(frozen=True)
class Import:
    """One import statement's target, resolved to an absolute dotted name."""

    source: str  # importing module (dotted), or the file path for files outside a package
    target: str  # the imported module, or its most specific known module
    line: int
    path: Path

    def where(self) -> str:
        return f'{self.path.relative_to(SRC.parent)}:{self.line}'


def module_name(root: Path, path: Path) -> str | None:
    """Dotted name of `path` below `root` (the folder holding the packages), or None."""
    parts = list(path.relative_to(root).with_suffix('').parts)
    if not parts or not (root / parts[0] / '__init__.py').is_file():
        return None
    if parts[-1] == '__init__':
        parts.pop()
    return '.'.join(parts)


def source_files(src: Path) -> dict[Path, tuple[str, str | None]]:
    """{file: (package, dotted module name or None)} for every non-test file of src/*/."""
    files = {}
    for package_dir in sorted(p for p in src.iterdir() if (p / 'package.xml').is_file()):
        for path in sorted(package_dir.rglob('*.py')):
            rel = path.relative_to(package_dir)
            if rel.parts[0] in ('test', 'build', 'install') or rel.name == 'setup.py':
                continue
            if any(part.endswith('.egg-info') for part in rel.parts):
                continue
            files[path] = (package_dir.name, module_name(package_dir, path))
    return files


def _resolve_relative(module: str, is_package: bool, level: int, name: str | None) -> str:
    base = module.split('.') if is_package else module.split('.')[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return '.'.join([*base, name] if name else base)


def imports_of(path: Path, module: str | None, known: set[str]) -> list[Import]:
    """Every import in `path`; `from a import b` targets a.b when that is a known module."""
    tree = ast.parse(path.read_text(encoding='utf-8'), filename=str(path))
    source = module or str(path)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [Import(source, alias.name, node.lineno, path) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if module is None:
                    raise AssertionError(f'{path}: relative import outside a package')
                is_package = path.name == '__init__.py'
                base = _resolve_relative(module, is_package, node.level, node.module)
            else:
                base = node.module or ''
            for alias in node.names:
                sub = f'{base}.{alias.name}'
                found.append(Import(source, sub if sub in known else base, node.lineno, path))
    return found


def collect(src: Path = SRC) -> tuple[dict[Path, tuple[str, str | None]], list[Import]]:
    files = source_files(src)
    known = {m for _, m in files.values() if m}
    found = []
    for path, (_, module) in files.items():
        found += imports_of(path, module, known)
    return files, found


def top(name: str) -> str:
    return name.split('.')[0]


def find_cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """One cycle [a, b, ..., a] of the directed graph, or None (iterative DFS)."""
    state: dict[str, int] = {}  # 1 = on the current path, 2 = done
    for start in sorted(edges):
        if state.get(start):
            continue
        path = [start]
        stack = [iter(sorted(edges.get(start, ())))]
        state[start] = 1
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                state[path.pop()] = 2
                stack.pop()
            elif state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                stack.append(iter(sorted(edges.get(nxt, ()))))
    return None


def package_graph(package: str, found: Iterable[Import], known: set[str]) -> dict[str, set[str]]:
    """Edges between the modules of one package (self-imports left out)."""
    edges: dict[str, set[str]] = {m: set() for m in known if top(m) == package}
    for imp in found:
        if imp.source in edges and imp.target in edges and imp.target != imp.source:
            edges[imp.source].add(imp.target)
    return edges


def package_edges(
    files: dict[Path, tuple[str, str | None]], found: Iterable[Import]
) -> dict[str, set[str]]:
    """{package: packages of the workspace it imports} (itself left out)."""
    packages = {package for package, _ in files.values()}
    edges: dict[str, set[str]] = {p: set() for p in packages}
    for imp in found:
        source, target = files[imp.path][0], top(imp.target)
        if target in packages and target != source:
            edges[source].add(target)
    return edges


def imports_of_package(package: str, banned: Iterable[str]) -> list[str]:
    """Where `package` imports one of the `banned` packages."""
    return sorted(
        {
            f'{imp.where()}: {imp.source} imports {imp.target}'
            for imp in IMPORTS
            if FILES[imp.path][0] == package and top(imp.target) in set(banned)
        }
    )


FILES, IMPORTS = collect()
KNOWN = {m for _, m in FILES.values() if m}
PACKAGES = sorted({package for package, _ in FILES.values()})


def test_the_source_tree_was_found() -> None:
    assert set(ROLE_PACKAGES) | {MODELS, 'mill_common', ANALYSIS, BRINGUP, BENCH} <= set(PACKAGES)
    assert 'mill_models.holds' in KNOWN and 'mill_plant.plant_node' in KNOWN


def test_role_packages_do_not_import_each_other() -> None:
    bad = sorted(
        {
            f'{imp.where()}: {imp.source} imports {imp.target}'
            for imp in IMPORTS
            if FILES[imp.path][0] in ROLE_PACKAGES
            and top(imp.target) in ROLE_PACKAGES
            and top(imp.target) != FILES[imp.path][0]
        }
    )
    assert not bad, 'role packages import each other (move the shared code to mill_models):\n' + (
        '\n'.join(bad)
    )


def test_models_are_ros_free() -> None:
    allowed_mill = {m for m in KNOWN if top(m) == MODELS} | set(ROS_FREE_COMMON)
    by_source: dict[str, list[Import]] = {}
    for imp in IMPORTS:
        by_source.setdefault(imp.source, []).append(imp)
    todo = sorted(m for m in KNOWN if top(m) == MODELS)
    seen = set(todo)
    bad = []
    while todo:
        module = todo.pop()
        for imp in by_source.get(module, []):
            name = top(imp.target)
            if name.startswith('mill_'):
                if imp.target not in allowed_mill:
                    bad.append(f'{imp.where()}: {module} imports {imp.target}')
                elif imp.target not in seen:  # follow mill_common's modules too
                    seen.add(imp.target)
                    todo.append(imp.target)
            elif name not in sys.stdlib_module_names and name not in MODELS_MAY_USE:
                bad.append(f'{imp.where()}: {module} imports {imp.target}')
    assert not bad, (
        'mill_models may use the standard library, numpy, scipy and '
        + ', '.join(ROS_FREE_COMMON)
        + ' only:\n'
        + '\n'.join(sorted(set(bad)))
    )


def test_analysis_imports_no_runner_benchmark_or_role_package() -> None:
    bad = imports_of_package(ANALYSIS, (BRINGUP, BENCH, *ROLE_PACKAGES))
    assert not bad, f'{ANALYSIS} reads records and bags only:\n' + '\n'.join(bad)


def test_bringup_does_not_import_the_benchmark() -> None:
    bad = imports_of_package(BRINGUP, (BENCH,))
    assert not bad, '\n'.join(bad)


def test_no_package_imports_the_benchmark() -> None:
    bad = [line for p in PACKAGES if p != BENCH for line in imports_of_package(p, (BENCH,))]
    assert not bad, f'{BENCH} is a leaf: nothing imports it\n' + '\n'.join(bad)


def test_no_import_cycle_between_packages() -> None:
    cycle = find_cycle(package_edges(FILES, IMPORTS))
    assert cycle is None, 'import cycle between packages: ' + ' -> '.join(cycle)


@pytest.mark.parametrize(
    'package',
    PACKAGES,
)
def test_no_import_cycle_within_a_package(package: str) -> None:
    cycle = find_cycle(package_graph(package, IMPORTS, KNOWN))
    assert cycle is None, f'import cycle in {package}: ' + ' -> '.join(cycle)


def test_the_checker_sees_relative_and_function_level_imports(tmp_path: Path) -> None:
    """A made-up package: a -> b at module level (relative), b -> a inside a function."""
    pkg = tmp_path / 'pkg_x'
    (pkg / 'pkg_x' / 'sub').mkdir(parents=True)
    (pkg / 'package.xml').write_text('<package/>')
    (pkg / 'pkg_x' / '__init__.py').write_text('')
    (pkg / 'pkg_x' / 'sub' / '__init__.py').write_text('')
    (pkg / 'pkg_x' / 'a.py').write_text('from .sub import b\nimport numpy\n')
    (pkg / 'pkg_x' / 'sub' / 'b.py').write_text('def f():\n    from .. import a\n    return a\n')
    (pkg / 'test').mkdir()
    (pkg / 'test' / 'test_a.py').write_text('import rclpy\n')
    files, found = collect(tmp_path)
    assert sorted(m for _, m in files.values()) == ['pkg_x', 'pkg_x.a', 'pkg_x.sub', 'pkg_x.sub.b']
    assert {(i.source, i.target) for i in found} == {
        ('pkg_x.a', 'pkg_x.sub.b'),
        ('pkg_x.a', 'numpy'),
        ('pkg_x.sub.b', 'pkg_x.a'),
    }
    known = {m for _, m in files.values() if m}
    assert find_cycle(package_graph('pkg_x', found, known)) == ['pkg_x.a', 'pkg_x.sub.b', 'pkg_x.a']


def test_the_checker_sees_a_cycle_between_packages(tmp_path: Path) -> None:
    """Made-up packages: pkg_a imports pkg_b inside a function, pkg_b imports pkg_a."""
    for name in ('pkg_a', 'pkg_b'):
        (tmp_path / name / name).mkdir(parents=True)
        (tmp_path / name / 'package.xml').write_text('<package/>')
        (tmp_path / name / name / '__init__.py').write_text('')
    (tmp_path / 'pkg_a' / 'pkg_a' / 'm.py').write_text('def f():\n    import pkg_b.n\n')
    (tmp_path / 'pkg_b' / 'pkg_b' / 'n.py').write_text('from pkg_a import m\n')
    files, found = collect(tmp_path)
    assert package_edges(files, found) == {'pkg_a': {'pkg_b'}, 'pkg_b': {'pkg_a'}}
    assert find_cycle(package_edges(files, found)) == ['pkg_a', 'pkg_b', 'pkg_a']
