"""The progress display off a terminal: plain lines with label, share or count; none early."""

from __future__ import annotations

import pytest
from mill_common.progress import Progress


def test_plain_lines_with_label_share_and_whole_counts(capsys: pytest.CaptureFixture) -> None:
    bar = Progress(598_823, unit='messages', label='run: reading', decimals=0)
    assert not bar.tty  # pytest captures stderr: the plain form
    bar.update(20_000)
    bar.update(40_000)  # within 5 s of the first line: not shown
    bar.close()
    assert capsys.readouterr().err == 'run: reading: 20000 / 598823 messages (3 %)\n'


def test_unknown_total_shows_the_count(capsys: pytest.CaptureFixture) -> None:
    bar = Progress(None, unit='messages', label='bag: reading', decimals=0)
    bar.update(1234)
    assert capsys.readouterr().err == 'bag: reading: 1234 messages\n'


def test_delay_keeps_a_short_task_silent(capsys: pytest.CaptureFixture) -> None:
    bar = Progress(10, unit='messages', decimals=0, delay=60.0)
    bar.update(10)
    bar.close()
    assert capsys.readouterr().err == ''


def test_runner_form_is_unchanged(capsys: pytest.CaptureFixture) -> None:
    bar = Progress(53.334)
    bar.update(1.5, 'real-time factor 0.40')
    assert capsys.readouterr().err == '1.50 / 53.33 s (3 %), real-time factor 0.40\n'
