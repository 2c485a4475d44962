"""Per-topic counts a writer notes in metadata.yaml (counts_note), read back by
Bag.noted_counts: how a run says which samples its record lacks."""

from __future__ import annotations

from pathlib import Path

from mill_bag.reader import open_bag
from mill_bag.writer import BagWriter, counts_note


def test_counts_notes_read_back_and_a_bag_without_one_has_none(tmp_path: Path) -> None:
    assert counts_note({'/b': 2, '/a': 0, '/c': 1}) == '{"/b": 2, "/c": 1}'
    notes = {'plain': 'x', 'counts': counts_note({'/b': 2}), 'broken': '[1, 2'}
    w = BagWriter(tmp_path / 'bag', custom_data=notes)
    w.close()
    bag = open_bag(tmp_path / 'bag')
    assert bag.noted_counts('counts') == {'/b': 2}
    assert bag.noted_counts('broken') is None and bag.noted_counts('plain') is None
    assert bag.noted_counts('absent') is None
