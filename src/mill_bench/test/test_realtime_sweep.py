"""benchmark --realtime: the rates, the runs' scenario, the drive's status read, the text."""

from __future__ import annotations

import math

import pytest
from mill_bench.drive_process import HopTimedJob, realtime_scenario
from mill_bench.realtime_figures import CRITERION, RatePoint
from mill_bench.realtime_sweep import parse_rates
from mill_bench.realtime_text import format_sweep
from mill_bringup.jobs.realtime import RealtimeAxisJob
from mill_bringup.jobs.registry import job_for


def test_rates_are_sorted_and_checked() -> None:
    assert parse_rates('1000,100,250,100') == [100.0, 250.0, 1000.0]
    with pytest.raises(ValueError, match="'fast' is not a rate"):
        parse_rates('100,fast')
    with pytest.raises(ValueError, match='outside'):
        parse_rates('0.5')
    with pytest.raises(ValueError, match='outside'):
        parse_rates('nan')


def test_every_rate_runs_on_the_wall_clock_with_the_rules_gains_and_a_drive_that_waits() -> None:
    scen = realtime_scenario('slotting', 250.0, 2.0)
    assert isinstance(job_for(scen), RealtimeAxisJob)  # not refused: no 1 kHz gains at 250 Hz
    for node in scen.nodes:
        values = scen.parameters(node.name)
        assert values['timing'] == 'realtime' and values['sample_period'] == 0.004
        assert scen.raw_parameters(node.name)['use_sim_time'] is False
    plant = scen.parameters('plant')
    assert plant['autostart'] is False  # activated by the runner, or by the floor
    assert scen.parameters('x_observer')['observer'] == 'eso'
    assert scen.parameters('x_controller')['pd.omega_c'] == 0.0  # 0: the rule's
    assert scen.parameters('y_observer')['command_delay'] == 1
    assert scen.parameters('trajectory')['duration'] == 2.0


def status(**axes: dict[str, str]) -> dict[str, str]:
    """A `plant: realtime` status as the listener hands it over: values as text."""
    values = {'overruns': '3', 'active_ticks': '1500', 'message': 'running', 'level': '0'}
    for axis, figures in axes.items():
        values |= {f'{axis}.{k}': v for k, v in figures.items()}
    return values


def figures(late: str, run: str, median: str, p99: str) -> dict[str, str]:
    return {
        'late_fraction': late,
        'longest_late_run': run,
        'latency_median_ms': median,
        'latency_p99_ms': p99,
        'latency_max_ms': '9.0',
    }


def test_the_drive_status_is_read_as_the_job_reads_it() -> None:
    job = HopTimedJob(realtime_scenario('slotting', 500.0, 2.0), lambda: 0.0)
    job.drive = status(
        x=figures('0.001', '1', '0.4', '0.8'),
        y=figures('0.004', '2', '0.6', '0.9'),
        z=figures('0.0', '0', '0.5', '1.2'),
    )
    p = job.point('floor', 500.0, 0.2, 0.3, ())
    assert (p.overruns, p.ticks, p.late_tick_fraction) == (3, 1500, 0.002)
    assert (p.late_fraction, p.longest_late_run) == (0.004, 2.0)
    assert (p.latency_median_ms, p.latency_p99_ms) == (0.6, 1.2)
    assert p.failed() == ['p99']
    job.drive = status(x=figures('0.0', '0', '0.4', '0.8'))  # y and z never reported
    assert math.isnan(job.point('floor', 500.0, 0.2, 0.3, ()).late_fraction)


class Listener:
    def __init__(self, drive: dict[str, str] | None) -> None:
        self.drive = drive

    def status(self, name: str) -> dict[str, str] | None:
        return self.drive if name == 'plant: realtime' else None


def test_the_figures_are_the_drives_first_status_after_the_job() -> None:
    job = HopTimedJob(realtime_scenario('slotting', 500.0, 2.0), lambda: 0.0)
    job.drive = status(x=figures('0.0', '0', '0.4', '0.8'))  # kept at the job's end
    after = status(x=figures('0.002', '1', '0.4', '0.9'))
    job.settled(Listener(None))  # type: ignore[arg-type]
    assert job.drive['x.late_fraction'] == '0.0'
    job.settled(Listener(after))  # type: ignore[arg-type]
    assert job.drive == after


def test_the_listener_times_states_and_estimates_too() -> None:
    job = HopTimedJob(realtime_scenario('slotting', 500.0, 2.0), lambda: 0.0)
    assert {'mill/y/state', 'mill/y/estimate', 'mill/y/joint_command'} <= job.timed_topics()


def made_up() -> list[RatePoint]:
    good = {'late_fraction': 0.0, 'longest_late_run': 0.0}
    fast = {**good, 'latency_median_ms': 0.25, 'latency_p99_ms': 0.5}
    slow = {**good, 'latency_median_ms': 1.5, 'latency_p99_ms': 4.25}
    loop = {'state': (0.2, 0.4), 'loop': (0.3, 0.6)}
    full = {**loop, 'observer': (0.35, 0.9), 'controller': (0.1, 0.2)}
    return [
        RatePoint('floor', 250.0, {'x': fast}, 0, 1000, {'x': loop}, 0.45, 0.5),
        RatePoint('single', 250.0, {'x': slow}, 1, 1000, {'x': full}, 0.5, 1.25),
        RatePoint('single', 500.0, {}, 0, 0, notes=('the run failed: the drive went silent',)),
    ]


def test_the_text_gives_cases_hops_and_verdicts_from_made_up_figures() -> None:
    text = '\n'.join(format_sweep(made_up(), ['single']))
    assert CRITERION in text
    lines = text.splitlines()
    floor = next(line for line in lines if line.split()[:3] == ['floor', '250', 'Hz'])
    assert floor.split() == [
        *('floor', '250', 'Hz', '0.00', '%', '0', '0.250', '0.500', '0', 'of', '1000'),
        *('(0.00', '%)', '0.450', '0.500', 'yes'),
    ]
    single = next(line for line in lines if line.split()[:3] == ['single', '250', 'Hz'])
    assert single.endswith('no: p99') and '1 of 1000 (0.10 %)' in single
    assert '  single 500 Hz: the run failed: the drive went silent' in lines
    hop_rows = [line.split() for line in lines if line.split()[3:4] == ['x']]
    assert hop_rows[0][4:] == ['0.200', '/', '0.400', '-', '-', '0.300', '/', '0.600']
    assert hop_rows[1][4:] == [
        *('0.200', '/', '0.400', '0.350', '/', '0.900', '0.100', '/', '0.200', '0.300', '/'),
        '0.600',
    ]
    assert 'No publish times are taken' in text
    assert lines[-2:] == [
        '  floor: 250 Hz',
        '  single: none of the rates tried (250 Hz missed: p99)',
    ]


def test_the_help_states_the_criterion(capsys: pytest.CaptureFixture[str]) -> None:
    from mill_bench.benchmark import main

    with pytest.raises(SystemExit) as exc:
        main(['--help'])
    assert exc.value.code == 0
    assert 'p99 state->command latency < 1 ms' in ' '.join(capsys.readouterr().out.split())
