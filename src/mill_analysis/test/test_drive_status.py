"""The values of a drive's status the runner reads, declared once (mill_analysis.drive_status):
every one is listed in the driver contract (docs/hardware-driver.md), and the runner reads
them through the declaration."""

from __future__ import annotations

import re
from pathlib import Path

from mill_analysis import drive_status as keys

PAGE = Path(__file__).resolve().parents[3] / 'docs' / 'hardware-driver.md'
SOURCES = Path(__file__).resolve().parents[3] / 'src'


def runner_table() -> dict[str, bool]:
    """The keys of the page's table "What the runner reads": key -> per axis."""
    text = PAGE.read_text()
    start = text.index('#### What the runner reads')
    rows = text[start:].split('\n\n')[2]  # the heading, the paragraph, then the table
    out = {}
    for row in rows.splitlines()[2:]:
        cells = [c.strip() for c in row.strip('|').split('|')]
        for key in re.findall(r'`([a-z0-9_]+)`', cells[0]):
            out[key] = cells[1] == 'yes'
    return out


def test_every_key_the_runner_reads_is_in_the_contract_and_no_other() -> None:
    table = runner_table()
    declared = {**dict.fromkeys(keys.PER_AXIS, True), **dict.fromkeys(keys.DRIVE, False)}
    assert table == declared


def test_the_contract_names_the_status_the_runner_reads() -> None:
    text = PAGE.read_text()
    assert f'`<drive>: {keys.PART}`' in text
    assert "WARNING: the drive plant sent statuses named plant: driver but none named 'plant: " in (
        ' '.join(text.split())
    )
    said = keys.misnamed(['plant: driver', 'plant: x axis'], 'plant')
    assert said.startswith(
        'the drive plant sent statuses named plant: driver, plant: x axis but none named '
        "'plant: realtime'"
    )
    assert keys.misnamed(['plant: realtime', 'plant: driver'], 'plant') == ''


def test_the_readers_take_the_keys_from_the_declaration() -> None:
    """No reader of a drive's status spells a key itself (a renamed key would be missed)."""
    readers = [
        SOURCES / 'mill_analysis' / 'mill_analysis' / 'events.py',
        SOURCES / 'mill_bringup' / 'mill_bringup' / 'jobs' / 'realtime.py',
    ]
    names = '|'.join([*keys.PER_AXIS, *keys.DRIVE])
    # `f'{axis}.stopped'`, `values.get('overruns'` (the kinds of event `'stopped'` are others)
    spelled = re.compile(rf"""\.(?:{names})['"]|get\(['"](?:{names})['"]""")
    for path in readers:
        assert spelled.findall(path.read_text()) == [], path
    assert spelled.findall("f'{axis}.stopped' drive.get('overruns', '0')") == [
        ".stopped'",
        "get('overruns'",
    ]
