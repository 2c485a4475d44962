"""docs/parameters.md is what the declarations give, and it lists every node's parameters."""

from __future__ import annotations

from pathlib import Path

from mill_bringup.catalogue import KINDS
from mill_bringup.docs_params import PAGE, main, page

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
    assert main(['--root', str(tmp_path), '--check']) == 1
    assert main(['--root', str(tmp_path), '--write']) == 0
    assert main(['--root', str(tmp_path), '--check']) == 0
