"""The distributed lockstep run equals the offline simulator (issue: time model)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mill_bringup import scenario


def tx_packets_off_loopback() -> int:
    """Packets sent so far through every interface but loopback (/proc/net/dev)."""
    total = 0
    for line in Path('/proc/net/dev').read_text().splitlines()[2:]:
        name, _, fields = line.partition(':')
        if name.strip() != 'lo':
            total += int(fields.split()[9])
    return total


@pytest.mark.system
def test_eight_process_run_equals_offline_simulation(ros_env, tmp_path):
    out = tmp_path / 'run'
    sent_before = tx_packets_off_loopback()
    proc = subprocess.run(
        [
            sys.executable,
            '-m',
            'mill_bringup.runner',
            'slotting',
            '--duration',
            '5',
            '--compare-offline',
            '--quiet',
            '--output',
            str(out),
        ],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    # DDS stayed on loopback: discovery of 9 participants off loopback would send
    # hundreds of packets; a stray neighbour-discovery packet of the OS is tolerated.
    assert tx_packets_off_loopback() - sent_before < 5
    summary = json.loads((out / 'summary.json').read_text())
    assert summary['samples'] == 5001  # t = 0 .. 5 s at 1 kHz, the start included
    assert summary['missing_samples'] == {}
    # Every sample of every axis: |e_distributed - e_offline| <= 1e-9 m.
    assert summary['offline_max_difference'] <= 1e-9
    # 8 node processes + the runner
    assert len(summary['peak_rss_mb']) == 9


# (scenario, duration [s], samples): every variant of each paper scenario, distributed
# against offline. Hatwesh runs past its load change at t = 1 s; its adaptive_pi_rls variant
# designs with the rls observer node's estimate (a fourth topic joined by the controller).
PAPER_RUNS = [
    ('chavez_conde', 1.0, 1001),
    ('maharof', 0.3, 3001),
    ('hatwesh', 1.1, 4401),
    # the velocity steps: the first two steps, the RLS warm-up and the first re-tuning
    ('hatwesh_velocity', 0.5, 2001),
]


@pytest.mark.system
@pytest.mark.parametrize(('name', 'duration', 'samples'), PAPER_RUNS)
def test_paper_scenario_runs_equal_offline(ros_env, tmp_path, name, duration, samples):
    out = tmp_path / 'run'
    proc = subprocess.run(
        [
            sys.executable,
            '-m',
            'mill_bringup.runner',
            name,
            '--duration',
            str(duration),
            '--compare-offline',
            '--quiet',
            '--output',
            str(out),
        ],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    variants = scenario.load(name).variants
    assert len(variants) >= 3
    for variant in variants:
        summary = json.loads((out / variant / 'summary.json').read_text())
        assert summary['samples'] == samples, variant
        assert summary['missing_samples'] == {}, variant
        assert summary['offline_max_difference'] <= 1e-9, variant
