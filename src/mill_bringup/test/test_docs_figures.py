"""Executable documentation: every marked figure of README.md and docs/*.md equals what its
command prints (mill_bringup.docs_figures), and the README image is current.

One test per group of figures, so pytest-xdist runs the groups side by side and each
group's offline runs happen once. The comparison is of the printed text, digit for digit:
the runs are deterministic, so a figure that differs is stale or its code changed.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest
from mill_bringup.docs_figures import image, markers
from mill_bringup.docs_figures.cli import documents, main
from mill_bringup.docs_figures.registry import GROUPS, MEASURED, compute, group_of

REPO = Path(__file__).resolve().parents[3]
# Each group's check runs on one xdist worker with the paper tests that share its runs
# (their module's xdist_group; scripts/test.sh passes --dist loadgroup).
SHARED = {
    'beltran_discretisation': 'beltran',
    'beltran_step': 'beltran',
    'beltran_specific_energy': 'beltran',
}  # the same runs
# The README's main job (its table and step response) is checked in CI; the other groups,
# minutes of offline runs on a 2-core machine, in the extended suite
# (`scripts/test.sh --all`, or `python -m mill_bringup.docs_figures.cli --check`).
IN_CI = {'beltran', 'beltran_step'}  # the README's table and its step response
OFFLINE = [
    pytest.param(
        name,
        marks=[pytest.mark.xdist_group(SHARED.get(name, name))]
        + ([] if name in IN_CI else [pytest.mark.slow]),
    )
    for name, g in sorted(GROUPS.items())
    if not g.system
]


def quoted() -> dict[str, list[markers.Figure]]:
    """Every marked figure of the docs, by document."""
    return {p.name: markers.find(p.read_text(encoding='utf-8')) for p in documents(REPO)}


def test_a_marker_is_read_up_to_the_end_of_its_figure() -> None:
    text = (
        'a <!-- fig g.a -->7.445 µm, <!-- fig g.b -->−0.49 %, <!-- fig g.c -->469 648 |\n'
        '<!-- fig g.d -->1.6e-12 N and <!-- fig g.e -->agrees: <!-- fig g.f -->'
    )
    found = markers.find(text)
    assert [(f.id, f.value, f.line) for f in found] == [
        ('g.a', '7.445', 1),
        ('g.b', '−0.49', 1),
        ('g.c', '469 648', 1),
        ('g.d', '1.6e-12', 2),
        ('g.e', 'agrees', 2),
        ('g.f', '', 2),
    ]
    new = markers.rewrite(text, {'g.a': '7.5', 'g.c': '1 000 000', 'g.f': 'x'})
    assert new.startswith('a <!-- fig g.a -->7.5 µm, <!-- fig g.b -->−0.49 %, ')
    assert '<!-- fig g.c -->1 000 000 |' in new and new.endswith('<!-- fig g.f -->x')
    assert markers.rewrite(new, {'g.a': '7.445', 'g.c': '469 648', 'g.f': ''}) == text


def test_a_misquoted_or_unknown_figure_is_named_with_its_line() -> None:
    text = 'x\n<!-- fig g.a -->7.445 µm <!-- fig g.b -->1'
    lines = markers.differences(text, {'g.a': '7.446'}, 'doc.md', lambda _: True)
    assert lines == [
        "doc.md:2: g.a: the docs say '7.445', the command prints '7.446'",
        'doc.md:2: g.b: no command prints this figure',
    ]


def test_every_marker_names_a_group_and_the_docs_have_markers() -> None:
    docs = quoted()
    assert {'README.md', 'papers.md'} <= docs.keys()
    unknown = [
        f'{d}:{f.line}: {f.id}'
        for d, figs in docs.items()
        for f in figs
        if group_of(f.id) not in GROUPS
    ]
    assert unknown == []
    assert {group_of(f.id) for f in docs['README.md']} >= {'beltran'}


@pytest.mark.parametrize('group', OFFLINE)
def test_the_docs_print_what_the_commands_print(group: str) -> None:
    figures = compute(group)
    mismatched, seen = [], set()
    for doc, found in quoted().items():
        for f in found:
            if group_of(f.id) != group:
                continue
            seen.add(f.id)
            if figures.get(f.id) != f.value:
                mismatched.append(f'{doc}:{f.line}: {f.id} {f.value!r} != {figures.get(f.id)!r}')
    assert mismatched == []
    assert sorted(set(figures) - seen) == []  # every figure printed is quoted somewhere


def test_the_command_line_refuses_a_tree_without_docs(tmp_path: Path, capsys) -> None:
    assert main(['--root', str(tmp_path), '--check']) == 2
    assert capsys.readouterr().err.count('\n') == 1


@pytest.mark.slow  # the main job's whole run (the extended suite)
def test_the_readme_image_is_drawn_from_the_current_run() -> None:
    # The data behind the plot, re-made from the run, equals the committed digest ...
    committed = (REPO / image.DATA).read_text(encoding='utf-8')
    assert image.data_text(image.offline(image.SCENARIO)) == committed
    # ... and the PNG was drawn from that digest (the hash image.py writes into it).
    assert image.png_data_hash(REPO / image.IMAGE) == hashlib.sha256(committed.encode()).hexdigest()


def test_the_timings_left_out_of_the_check_are_still_in_the_docs() -> None:
    """registry.MEASURED names each machine-dependent figure the check leaves out; a phrase
    that left its document means the list is stale."""
    missing = [m for m in MEASURED if m.text not in (REPO / m.document).read_text('utf-8')]
    assert missing == []
