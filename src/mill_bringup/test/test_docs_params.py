"""docs/parameters.md is what the declarations give, and it lists every node's parameters."""

from __future__ import annotations

from pathlib import Path

from mill_bringup.catalogue import KINDS
from mill_bringup.docs_params import GUIDE, PAGE, launch_table, main, page

REPO = Path(__file__).resolve().parents[3]


def test_the_page_is_current() -> None:
    assert main(['--root', str(REPO), '--check']) == 0, 'run: docs_params --write'


def test_every_parameter_of_every_node_has_a_row() -> None:
    text = page()
    for kind in KINDS:
        for name, _spec in kind.parameter_specs():
            assert f'| `{name}` |' in text, (kind.executable, name)


def test_a_stale_page_is_found(tmp_path: Path) -> None:
    (tmp_path / PAGE).parent.mkdir()
    (tmp_path / PAGE).write_text(page().replace('read-only', 'yes', 1), encoding='utf-8')
    (tmp_path / GUIDE).write_text((REPO / GUIDE).read_text(encoding='utf-8'), encoding='utf-8')
    assert main(['--root', str(tmp_path), '--check']) == 1
    assert main(['--root', str(tmp_path), '--write']) == 0
    assert main(['--root', str(tmp_path), '--check']) == 0


def test_the_launch_table_has_every_declared_argument_and_a_stale_one_is_found(
    tmp_path: Path,
) -> None:
    from mill_bringup.launch_plan import ARGUMENTS

    table = launch_table().splitlines()
    assert [row.split('|')[1].strip() for row in table[2:]] == [f'`{a.name}`' for a in ARGUMENTS]
    assert len(table) == 2 + len(ARGUMENTS) == 10  # eight arguments (the guide once said five)
    (tmp_path / PAGE).parent.mkdir()
    (tmp_path / PAGE).write_text(page(), encoding='utf-8')
    current = (REPO / GUIDE).read_text(encoding='utf-8')
    row = next(r for r in table if r.startswith('| `private_clock`'))
    (tmp_path / GUIDE).write_text(current.replace(row + '\n', ''), encoding='utf-8')
    assert main(['--root', str(tmp_path), '--check']) == 1  # a row gone: stale
    assert main(['--root', str(tmp_path), '--write']) == 0
    assert (tmp_path / GUIDE).read_text(encoding='utf-8') == current
    assert main(['--root', str(tmp_path), '--check']) == 0
