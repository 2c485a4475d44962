"""Every package declares in its package.xml what it needs, so that `rosdep install
--from-paths src` installs it; checked on the source (ast; only the catalogue and the job
kinds are imported, to read what they name).

What a package needs:

- every module it imports, at module level or inside functions (test files: test_depend);
  its launch files' imports too. A module is declared as the package of its name (rclpy,
  sensor_msgs, launch_ros, mill_common, ...), a Python library by its rosdep key
  (PYTHON_KEYS);
- every module it runs with `python -m MODULE`;
- mill_bringup: the packages of the nodes its launch file and runner start (the node
  catalogue), and the message packages of the topics the runner's monitor subscribes to by
  type name (mill_bag.recorder.message_class).

Every Python library is declared by its rosdep key, all in one table (PYTHON_KEYS): the
keys of rosdistro's rosdep/python.yaml, and those it lacks defined in this workspace's
rosdep/mill.yaml (a test checks that each is, with the pip package that provides it). A
test that imports a package which itself test_depends on this one cannot declare it: colcon
orders packages by every kind of dependency and refuses the cycle. Nothing may be declared
that the package does not need (a stale dependency hides a missing one), but for the
entries of KNOWN_UNUSED.
"""

from __future__ import annotations

import ast
import functools
import itertools
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from test.test_import_graph import imports_of, module_name

SRC = Path(__file__).resolve().parents[1] / 'src'
PACKAGES = sorted(p.parent.name for p in SRC.glob('*/package.xml'))
# Python libraries (top-level import name) by their rosdep keys: those of rosdistro's
# rosdep/python.yaml (checked there), else of this workspace's rosdep/mill.yaml (LOCAL_KEYS).
PYTHON_KEYS = {
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'yaml': 'python3-yaml',
    'matplotlib': 'python3-matplotlib',
    'PIL': 'python3-pil',
    'tqdm': 'python3-tqdm',
    'pytest': 'python3-pytest',
    'hypothesis': 'python3-hypothesis',
    'rosbags': 'python3-rosbags-pip',  # rosdistro: pip rosbags
    'mcap_ros2': 'mcap-ros2-support',  # rosdistro: pip mcap-ros2-support
    'mcap': 'python3-mcap-pip',  # not in rosdistro: rosdep/mill.yaml, pip mcap
    'control': 'python3-control-pip',  # not in rosdistro: rosdep/mill.yaml, pip control
}
# The keys rosdistro lacks: defined in rosdep/mill.yaml, with the pip package of each.
LOCAL_KEYS = {'python3-mcap-pip': 'mcap', 'python3-control-pip': 'control'}
ROSDEP_FILE = SRC.parent / 'rosdep' / 'mill.yaml'
WORKSPACE_TESTS = 'test'  # the workspace's test/ package (its conftest), not a dependency
# Declared, not imported: provided through another dependency, left to the package's owners.
KNOWN_UNUSED = {('mill_common', 'std_msgs')}  # sensor_msgs brings it (JointState's header)


def key_of(module: str) -> str | None:
    """The rosdep key that provides a module (None: the standard library, the workspace)."""
    top = module.split('.')[0]
    if top in sys.stdlib_module_names or top == WORKSPACE_TESTS:
        return None
    return PYTHON_KEYS.get(top, top)


def run_modules(tree: ast.AST) -> set[str]:
    """Modules a file runs as `python -m MODULE`: the text after '-m' in a list or tuple."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.List | ast.Tuple):
            items = node.elts
            for a, b in itertools.pairwise(items):
                if (
                    isinstance(a, ast.Constant)
                    and a.value == '-m'
                    and isinstance(b, ast.Constant)
                    and isinstance(b.value, str)
                ):
                    found.add(b.value)
    return found


@functools.cache
def by_name() -> dict[str, set[str]]:
    """What mill_bringup needs that no import shows (see the module doc)."""
    from mill_bag.types import CLOCK, DIAGNOSTIC_ARRAY
    from mill_bringup.jobs.registry import job_for

    from mill_bringup import catalogue, scenario

    needs = {k.package for k in catalogue.KINDS}
    types = {CLOCK, DIAGNOSTIC_ARRAY}  # the monitor's own subscriptions
    for path in sorted((SRC.parent / 'config').glob('*.yaml')):
        scen = scenario.load(path.stem)
        for variant in [scen, *(scen.variant(name) for name in scen.variants)]:
            job = job_for(variant)
            plan = job.graph_plan()
            types |= {*plan.kept.values(), *plan.recorded.values()}
    needs |= {t.split('/')[0] for t in types}
    return {'mill_bringup': needs}


@functools.cache
def needed(package: str) -> tuple[dict[str, str], dict[str, str]]:
    """(run-time needs, test needs): rosdep key -> the first file that needs it."""
    root = SRC / package
    run: dict[str, str] = {}
    test: dict[str, str] = {}
    for path in sorted(root.rglob('*.py')):
        rel = path.relative_to(root)
        if rel.name == 'setup.py' or rel.parts[0] in ('build', 'install'):
            continue
        if any(part.endswith('.egg-info') for part in rel.parts):
            continue
        into = test if rel.parts[0] == 'test' else run
        module = module_name(root, path) if rel.parts[0] == package else None
        targets = {i.target for i in imports_of(path, module, set())}
        targets |= run_modules(ast.parse(path.read_text(encoding='utf-8')))
        siblings = {p.stem for p in path.parent.glob('*.py')}  # tests import one another
        for target in targets - siblings:
            key = key_of(target)
            if key is not None and key != package:
                into.setdefault(key, str(rel))
    for key in by_name().get(package, ()):
        if key != package:
            run.setdefault(key, 'named in its code (see the module doc)')
    return run, test


def declared(package: str) -> tuple[set[str], set[str]]:
    """(exec, test) dependencies of package.xml (depend counts as both)."""
    root = ET.parse(SRC / package / 'package.xml').getroot()

    def of(*tags: str) -> set[str]:
        return {(e.text or '').strip() for tag in tags for e in root.findall(tag)}

    return of('depend', 'exec_depend'), of('depend', 'test_depend')


def depends_on(package: str, other: str) -> bool:
    """Whether `package` depends on `other`, directly or not, by any declared dependency."""
    todo, seen = [package], set()
    while todo:
        name = todo.pop()
        exec_deps, test_deps = declared(name)
        for dep in ((exec_deps | test_deps) & set(PACKAGES)) - seen:
            if dep == other:
                return True
            seen.add(dep)
            todo.append(dep)
    return False


@pytest.mark.parametrize('package', PACKAGES)
def test_package_xml_declares_what_the_package_needs(package: str) -> None:
    run, test = needed(package)
    exec_deps, test_deps = declared(package)
    missing = [f'exec_depend {k} ({run[k]})' for k in sorted(set(run) - exec_deps)]
    for key in sorted(set(test) - exec_deps - test_deps):
        if key not in PACKAGES or not depends_on(key, package):  # else: a cycle
            missing.append(f'test_depend {key} ({test[key]})')
    assert not missing, f'{package}/package.xml lacks:\n' + '\n'.join(missing)


@pytest.mark.parametrize('package', PACKAGES)
def test_package_xml_declares_nothing_the_package_does_not_need(package: str) -> None:
    run, test = needed(package)
    exec_deps, test_deps = declared(package)
    unused = (exec_deps | test_deps) - set(run) - set(test)
    stale = [k for k in sorted(unused) if (package, k) not in KNOWN_UNUSED]
    assert not stale, f'{package}/package.xml declares what it does not use:\n' + '\n'.join(stale)


def test_the_checker_sees_imports_in_functions_launch_files_and_python_m(tmp_path: Path) -> None:
    tree = ast.parse("cmd = [sys.executable, '-m', 'mill_analysis.report', bag]\n")
    assert run_modules(tree) == {'mill_analysis.report'}
    assert key_of('yaml') == 'python3-yaml' and key_of('launch_ros.actions') == 'launch_ros'
    assert key_of('os.path') is None and key_of('rosbags.rosbag2') == 'python3-rosbags-pip'
    assert key_of('mcap.writer') == 'python3-mcap-pip'
    run, _ = needed('mill_bringup')
    assert {'launch', 'launch_ros', 'lifecycle_msgs', 'mill_plant', 'rosgraph_msgs'} <= set(run)


def test_every_key_rosdistro_lacks_is_defined_in_the_workspace_rosdep_file() -> None:
    import yaml

    rules = yaml.safe_load(ROSDEP_FILE.read_text())
    assert set(rules) == set(LOCAL_KEYS) <= set(PYTHON_KEYS.values())
    for key, package in LOCAL_KEYS.items():
        for os_name in ('debian', 'ubuntu', 'fedora', 'osx'):
            assert rules[key][os_name] == {'pip': {'packages': [package]}}, (key, os_name)
    # and requirements.txt, which the venv is installed from, names each pip package too
    required = (SRC.parent / 'requirements.txt').read_text()
    for package in [*LOCAL_KEYS.values(), 'rosbags', 'mcap-ros2-support']:
        assert f'\n{package}' in required, package
