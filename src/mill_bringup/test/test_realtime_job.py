"""How the commands of a realtime run answered the job's states (the runner's summary, the
report of a bag): realtime_record.command_timing."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from mill_analysis.events import Status
from mill_analysis.record import RunRecord
from mill_bringup.cli import set_timing
from mill_bringup.jobs.base import Ending
from mill_bringup.jobs.realtime import (
    RealtimeAxisJob,
    drive_figures,
    drive_stalls,
    drive_ticks,
)
from mill_bringup.jobs.registry import job_for
from mill_bringup.tuning.prediction_file import prediction_path
from mill_common.timebase import job_steps

from mill_bringup import scenario
from mill_common import topics

T0 = 1_800_000_000_000_000_000  # the job's start on the system clock [ns]
DT = 10_000_000


@pytest.mark.parametrize(
    'name', ['slotting', 'chavez_conde', 'hatwesh', 'hatwesh_velocity', 'maharof']
)
def test_every_axis_scenario_can_start_in_realtime(name: str) -> None:
    """The trajectory starts a realtime job once its `axes` report their positions: in a
    one-axis scenario they must be the plant's one axis, or the job never starts."""
    scen = scenario.load(name)
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)


def test_a_trajectory_waiting_for_other_axes_than_the_plant_drives_is_refused() -> None:
    scen = scenario.load('chavez_conde')
    set_timing(scen, 'realtime')
    scen.add_override('trajectory.axes=["x", "y"]')
    with pytest.raises(scenario.ScenarioError, match=r'set trajectory\.axes'):
        job_for(scen)


def test_the_drives_late_ticks_come_with_its_own_tick_count() -> None:
    """Late ticks are counted from the drive's activation on (approach and hold included):
    their share is taken of the drive's ticks over the same span, not of the job's samples."""
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    assert drive_ticks({}) == (0, 0)  # a driver that reports neither
    assert drive_ticks({'overruns': '3', 'active_ticks': '600'}) == (3, 600)
    figures = drive_figures(job.axes, {'overruns': '3', 'active_ticks': '600'})
    assert (figures.overruns, figures.ticks) == (3, 600)


def test_a_run_that_starts_with_an_approach_is_compared_with_the_prediction_after_it(
    tmp_path,
) -> None:
    """The prediction runs the job's path alone (offline, no approach); the run first moves
    to the path's start: its figures, and the comparison, are over the window after it."""
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    dt = job.dt_ns * 1e-9
    path_end = (job_steps(job.end_time, job.dt_ns) - 1) * dt
    params = tmp_path / 'tuned.yaml'
    params.write_text('{}\n')
    scen.params_files.append(str(params))
    prediction = {
        'scenario': 'slotting',
        'sample_period': dt,
        'skip': 1.0,
        'end': path_end,
        'rms_error': {'x': 10e-6, 'y': 10e-6, 'z': 10e-6},
        'max_error': {'x': 20e-6, 'y': 20e-6, 'z': 20e-6},
        'events': [],
        'overrides': [],
    }
    prediction_path(params).write_text(yaml.safe_dump(prediction))
    approach = 0.75
    n = round((approach + path_end) / dt) + 1
    rec = RunRecord.empty(n, dt)
    rec.signals['reference'][:] = 0.0
    rec.signals['position'][:] = np.where(rec.t[:, None] < approach, 3e-3, 20e-6)
    job_status = Status(
        T0,
        f'{job.trajectory}: {topics.JOB_STATUS}',
        0,
        'job done',
        {'state': 'done', 'start_stamp_ns': str(T0), 'approach_s': repr(approach)},
    )
    summary = job.summary(rec, 1.0, Ending((job_status,)))
    assert summary.approach == approach and summary.window.start == approach + 1.0
    (compared,) = summary.predictions
    assert not compared.note, compared.note
    assert compared.measured == pytest.approx({a: 20e-6 for a in 'xyz'})
    line = compared.lines()[0]
    assert line.startswith('RMS e [µm] measured / predicted by tune') and '(2.00x)' in line
    assert all(m.max_error == pytest.approx(20e-6) for m in summary.axes)  # not the 3 mm
    # Counted from the record's start, as before, the run ended an approach later than the
    # prediction: never compared.
    before = job.summary(rec, 1.0, Ending())
    assert before.predictions[0].note.endswith('not compared')


def test_the_drives_own_stalls_are_said_as_what_they_were() -> None:
    """A drive that reports its stalls (ticks that woke late on the monotonic clock): their
    number and the longest, with which process and when, as the drive said it."""
    scen = scenario.load('slotting')
    set_timing(scen, 'realtime')
    job = job_for(scen)
    assert isinstance(job, RealtimeAxisJob)
    assert drive_stalls({}) == (0, 0.0, '')  # a driver that does not report them
    line = 'drive plant (pid 4242) stalled 112 ms (monotonic) at 22:31:07.015 UTC'
    drive = {'stalls': '2', 'longest_stall_ms': '112.0', 'longest_stall': line}
    assert drive_stalls(drive) == (2, 112.0, line)
    figures = drive_figures(job.axes, drive | {'stall_report_ms': '50.0'})
    assert figures.lines()[-1] == (
        f'WARNING: the drive stalled 2 times by more than 50.0 ms (monotonic), the longest: '
        f'{line}; its own stalls, not late commands'
    )
