"""Build the interface package interfaces/mill_interfaces into the PyPI-wheel venv.

The ROS 2 Jazzy wheels ship the rosidl generators (rosidl_cli, rosidl_generator_c/py,
the type supports) and the C headers and libraries under the venv's include/ and lib/, but
not ament_cmake, which a colcon build of an interface package needs. This does what
rosidl_generate_interfaces does for the Python side, with the C compiler:

1. generate the C, introspection, Fast DDS and Python sources (rosidl_cli's Python API);
2. compile the C libraries lib<pkg>__rosidl_generator_c, __rosidl_typesupport_c,
   __rosidl_typesupport_introspection_c, __rosidl_typesupport_fastrtps_c into <venv>/lib,
   beside those of std_srvs, and the three Python extensions into site-packages/<pkg>/;
3. register the package in the ament index (share/ament_index/resource_index) with its
   .srv, .action and .idl files and package.xml, as a colcon install does.

The Python extensions link all three type-support libraries, so that rmw's dlopen finds
them loaded already (no LD_LIBRARY_PATH). Two quirks of rosidl_cli 4.6.6 from the wheels
are worked around here: rosidl_generator_py's entry point is found twice (an egg-info and a
dist-info), and generate() wants a pathlib.Path for its output.

Usage: python scripts/build_interfaces.py [--venv DIR] [--package DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.metadata
import io
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
TYPESUPPORTS = ('c', 'introspection_c', 'fastrtps_c')
KINDS = ('srv', 'action')  # the interface folders, each file named <Type>.<folder>
# the interface packages the generated code depends on (an action: its goal id and status)
DEPENDENCIES = ('service_msgs', 'builtin_interfaces', 'action_msgs', 'unique_identifier_msgs')


def _generate(package: Path, name: str, venv: Path, out: Path) -> list[str]:
    """Generated sources under out/<kind>/; returns the interface files (srv/X.srv)."""
    import rosidl_cli.entry_points as entry_points

    def unique(group_name: str, *, specs: Any = None, strict: bool = False) -> dict[str, Any]:
        found: dict[str, Any] = {}
        for e in importlib.metadata.entry_points(group=group_name):
            found.setdefault(e.name, e)  # the same entry point, listed twice
        return found

    entry_points.get_entry_points = unique  # type: ignore[assignment]
    from rosidl_cli.command.generate.api import generate

    files = sorted(str(p.relative_to(package)) for k in KINDS for p in (package / k).glob(f'*.{k}'))
    os.environ['AMENT_PREFIX_PATH'] = str(venv)
    here = os.getcwd()
    os.chdir(package)
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # a line per file read and written
            generate(
                package_name=name,
                interface_files=files,
                include_paths=[str(venv / 'share')],
                output_path=out,
                types=['c', 'py'],
                typesupports=list(TYPESUPPORTS),
            )
    finally:
        os.chdir(here)
    return files


def _run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f'build_interfaces: {cmd[0]} failed:\n{proc.stderr.strip()}')


def build(package: Path, venv: Path) -> None:
    name = package.name
    cc = os.environ.get('CC', 'cc')
    cxx = os.environ.get('CXX', 'c++')
    for tool in (cc, cxx):
        if shutil.which(tool) is None:
            sys.exit(f'build_interfaces: no C/C++ compiler {tool!r}: install gcc and g++')
    lib = venv / 'lib'
    site = Path(sysconfig.get_paths()['purelib'])
    suffix = sysconfig.get_config_var('EXT_SUFFIX')
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        out = work / 'out'
        files = _generate(package, name, venv, out)
        inc = work / 'include' / name
        for kind in ('c', 'introspection_c', 'fastrtps_c'):
            shutil.copytree(out / kind, inc, dirs_exist_ok=True)
        includes = [f'-I{work / "include"}', f'-I{venv / "include"}']
        includes += [f'-I{d}' for d in sorted((venv / 'include').iterdir()) if d.is_dir()]
        flags = ['-shared', '-fPIC', '-O2', *includes, f'-L{lib}', '-Wl,-rpath,$ORIGIN']
        base = [f'-l{d}__rosidl_generator_c' for d in DEPENDENCIES]
        base += ['-lrosidl_runtime_c', '-lrcutils']
        own = f'-l{name}__rosidl_generator_c'
        kinds = sorted({Path(f).parent.name for f in files})

        def sources(kind: str, pattern: str, sub: str = 'detail') -> list[Path]:
            return sorted(p for k in kinds for p in (out / kind / k / sub).glob(pattern))

        def deps(suffix: str) -> list[str]:
            return [f'-l{d}__rosidl_typesupport_{suffix}' for d in DEPENDENCIES]

        def link(tool: str, sources: list[Path], output: Path, *libs: str) -> None:
            _run([tool, *flags, *map(str, sources), '-o', str(output), *libs, *base])

        link(cc, sources('c', '*.c'), lib / f'lib{name}__rosidl_generator_c.so')
        link(
            cc,
            sources('introspection_c', '*.c'),
            lib / f'lib{name}__rosidl_typesupport_introspection_c.so',
            own,
            *deps('introspection_c'),
            '-lrosidl_typesupport_introspection_c',
        )
        link(
            cxx,
            sources('fastrtps_c', '*.cpp'),
            lib / f'lib{name}__rosidl_typesupport_fastrtps_c.so',
            own,
            *deps('fastrtps_c'),
            '-lrosidl_typesupport_fastrtps_c',
            '-lrosidl_typesupport_fastrtps_cpp',
            '-lfastcdr',
            '-lrmw',
        )
        link(
            cxx,
            sources('c', '*.cpp', ''),
            lib / f'lib{name}__rosidl_typesupport_c.so',
            own,
            *deps('c'),
            '-lrosidl_typesupport_c',
            '-lrcpputils',
        )
        target = site / name
        if target.exists():
            shutil.rmtree(target)
        shutil.copytree(out / 'py', target, ignore=shutil.ignore_patterns('*.c', 'tmp'))
        (target / '__init__.py').touch()
        python = [f'-I{sysconfig.get_paths()["include"]}']
        import numpy

        python.append(f'-I{numpy.get_include()}')
        py_sources = sorted(p for k in kinds for p in (out / 'py' / k).glob('*_s.c'))
        # site-packages/<name>/ -> <venv>/lib, where the libraries are.
        rpath = f'-Wl,-rpath,$ORIGIN/{os.path.relpath(lib, target)}'
        everyone = [f'-l{name}__rosidl_typesupport_{ts}' for ts in TYPESUPPORTS]
        for ts in TYPESUPPORTS:
            entry = out / 'py' / f'_{name}_s.ep.rosidl_typesupport_{ts}.c'
            module = target / f'{name}_s__rosidl_typesupport_{ts}{suffix}'
            link(
                cc,
                [entry, *py_sources],
                module,
                *python,
                rpath,
                own,
                '-Wl,--no-as-needed',
                *everyone,
                '-Wl,--as-needed',
                *(f'-l{d}__rosidl_generator_py' for d in DEPENDENCIES),
            )
        share = venv / 'share' / name
        shutil.rmtree(share, ignore_errors=True)
        share.mkdir(parents=True)
        shutil.copy(package / 'package.xml', share / 'package.xml')
        listed = []
        for f in files:
            kind, stem = Path(f).parent.name, Path(f).stem
            (share / kind).mkdir(exist_ok=True)
            shutil.copy(package / f, share / kind / f'{stem}.{kind}')
            shutil.copy(out / 'c' / 'tmp' / kind / f'{stem}.idl', share / kind / f'{stem}.idl')
            listed += [f'{kind}/{stem}.idl', f'{kind}/{stem}.{kind}']
        index = venv / 'share' / 'ament_index' / 'resource_index'
        for kind, text in (('packages', ''), ('rosidl_interfaces', '\n'.join(listed) + '\n')):
            (index / kind).mkdir(parents=True, exist_ok=True)
            (index / kind / name).write_text(text)
    print(f'build_interfaces: {name} ({", ".join(files)}) built into {venv}')


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--venv', type=Path, default=Path(sys.prefix))
    parser.add_argument('--package', type=Path, default=ROOT / 'interfaces' / 'mill_interfaces')
    args = parser.parse_args(argv)
    build(args.package.resolve(), args.venv.resolve())
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
