"""run_scenario --stay (issue 34, item 5): after a realtime job the graph stays up for manual
commands until Ctrl-C or SIGTERM, which end the run as that of a complete job; a lockstep job
is refused in one line before anything starts."""

from __future__ import annotations

from typing import Any

import pytest
from mill_bringup.runner.cli import STAY_NEEDS_REALTIME, main, parser, run_options
from mill_bringup.runner.follow import stay
from mill_bringup.runner.result import START_REFUSED


def test_stay_is_off_by_default_and_refused_with_a_lockstep_job(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert not run_options(parser().parse_args(['slotting']), None).stay
    assert run_options(parser().parse_args(['slotting', '--stay']), None).stay
    assert main(['slotting', '--stay', '--duration', '0.3']) == START_REFUSED
    assert capsys.readouterr().err == f'run_scenario: error: {STAY_NEEDS_REALTIME}\n'


class Session:
    """What `stay` uses of the runner's session: spins until the third is interrupted."""

    def __init__(self) -> None:
        self.spins = 0
        self.taken = False
        self.notes: list[str] = []
        self.progress = self
        self.monitor = object()

    def note(self, text: str) -> None:
        self.notes.append(text)

    def spin(self, when: str) -> None:
        self.spins += 1
        if self.spins == 3:
            raise KeyboardInterrupt

    def take_stop(self) -> None:
        self.taken = True


class Job:
    def __init__(self) -> None:
        self.checked = 0

    def check(self, monitor: Any) -> None:
        self.checked += 1


def test_the_stay_checks_the_job_until_a_stop_which_ends_it_as_a_complete_run() -> None:
    session, job = Session(), Job()
    stay(session, job)  # type: ignore[arg-type]
    assert (session.spins, job.checked, session.taken) == (3, 2, True)
    assert session.notes == [
        'the job is done; the graph stays up for manual commands (--stay) until Ctrl-C'
    ]


def test_a_failing_check_during_the_stay_ends_the_run_as_the_job_would() -> None:
    class Silent(Job):
        def check(self, monitor: Any) -> None:
            raise RuntimeError('the drive went silent')

    with pytest.raises(RuntimeError, match='the drive went silent'):
        stay(Session(), Silent())  # type: ignore[arg-type]
