"""Parameters round-trip on a running graph, as `ros2 param dump` and `ros2 param load` do
it, from a client node of its own (rclpy's parameter services; ros2cli is not on PyPI):

dump (ListParameters, then GetParameters of every listed name) -> load (SetParameters of
every dumped value, as `ros2 param load` sends a dump back) -> dump again: the two dumps
are equal, every writable value is taken, every read-only one refused in one line and left
as it was. The axis controller runs pd, which trips on its following error: its trip,
latched before the load, stays latched after it (only ~/reset_trip re-arms an axis), so
its commands stay NaN (the brake request).
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path
from typing import Any

import pytest
from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from rclpy.parameter import Parameter, parameter_value_to_python

from mill_bringup import launch_plan
from mill_common import topics
from test.conftest import ros_node, spin_until
from test.test_job_watch import launched

NS = 'machine_p'
NODES = ('x_controller', 'x_observer', 'trajectory', 'plant')


class Services:
    """ros2 param dump / load of one remote node, through its parameter services."""

    def __init__(self, node: Any, executor: Any, target: str) -> None:
        self.executor = executor
        base = f'/{NS}/{target}'
        self.clients = {
            kind: node.create_client(kind, f'{base}/{service}')
            for kind, service in (
                (ListParameters, 'list_parameters'),
                (GetParameters, 'get_parameters'),
                (SetParameters, 'set_parameters'),
                (DescribeParameters, 'describe_parameters'),
            )
        }

    def wait(self) -> None:
        for client in self.clients.values():
            assert client.wait_for_service(timeout_sec=60), client.srv_name

    def call(self, kind: Any, request: Any) -> Any:
        client = self.clients[kind]
        future = client.call_async(request)
        self.executor.spin_until_future_complete(future, timeout_sec=30)
        assert future.done(), f'{client.srv_name} did not answer'
        return future.result()

    def dump(self) -> dict[str, Any]:
        names = list(self.call(ListParameters, ListParameters.Request()).result.names)
        values = self.call(GetParameters, GetParameters.Request(names=names)).values
        assert len(values) == len(names), 'GetParameters answered fewer values than asked'
        return {n: parameter_value_to_python(v) for n, v in zip(names, values, strict=True)}

    def read_only(self, names: list[str]) -> set[str]:
        described = self.call(DescribeParameters, DescribeParameters.Request(names=names))
        return {n for n, d in zip(names, described.descriptors, strict=True) if d.read_only}

    def load(self, values: dict[str, Any]) -> dict[str, Any]:
        """Every value sent back in one request; name -> its SetParametersResult."""
        request = SetParameters.Request()
        request.parameters = [Parameter(n, value=v).to_parameter_msg() for n, v in values.items()]
        results = self.call(SetParameters, request).results
        return dict(zip(values, results, strict=True))


def _start(tmp_path: Path, env: dict[str, str]) -> dict[str, subprocess.Popen[str]]:
    params = tmp_path / 'pd.yaml'  # pd on x: it trips on its following error (as offline)
    params.write_text('/**/x_controller:\n  ros__parameters:\n    controller: pd\n')
    plan = launch_plan.plan('slotting', NS, str(params), '', 'warn', 'processes', 'true')
    launch_plan.write_parameters(plan, str(tmp_path))
    return {
        n.name: subprocess.Popen(
            launched(n), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        for n in plan.nodes
    }


@pytest.mark.system
@pytest.mark.serial  # "the load held no node up": no WARN, timing under load
def test_dump_load_dump_restores_every_node_and_keeps_a_trip_latched(ros_env, tmp_path):
    from sensor_msgs.msg import JointState

    procs: dict[str, subprocess.Popen[str]] = {}
    try:
        with ros_node('param_round_trip') as (node, executor):
            efforts: list[float] = []
            node.create_subscription(
                JointState,
                topics.qualify(topics.joint_command('x'), NS),
                lambda m: efforts.append(m.effort[0] if len(m.effort) else math.nan),
                100,
            )
            # Every client is there before the graph starts: a participant or client that
            # joins a running lockstep graph holds it up by itself (docs/performance.md, "A
            # participant joining the domain holds the graph up"; mill_bench.joiner), which
            # is not what this test is about.
            remote = {target: Services(node, executor, target) for target in NODES}
            procs.update(_start(tmp_path, ros_env))
            # pd trips x within the job's first 0.3 s: its commands become NaN
            assert spin_until(executor, lambda: any(math.isnan(e) for e in efforts), 300), (
                'x never tripped'
            )
            for target in NODES:
                services = remote[target]
                services.wait()
                first = services.dump()
                assert first and all(v is not None for v in first.values()), target
                read_only = services.read_only(list(first))
                assert 0 < len(read_only) < len(first), target  # both kinds are sent back
                if target == 'x_controller':
                    assert first['controller'] == 'pd' and 'following_error_limit' in first
                    assert 'following_error_limit' not in read_only
                results = services.load(first)
                for name, result in results.items():
                    if name in read_only:
                        assert not result.successful and '\n' not in result.reason, name
                    else:
                        assert result.successful, (target, name, result.reason)
                second = services.dump()
                assert second == first, {
                    n: (first[n], second.get(n)) for n in first if second.get(n) != first[n]
                }
            # the trip latched before the load is latched after it: NaN commands go on
            seen = len(efforts)
            assert spin_until(executor, lambda: len(efforts) >= seen + 50, 120)
            assert all(math.isnan(e) for e in efforts[seen:]), efforts[seen:][:10]
        for name, proc in procs.items():
            assert proc.poll() is None or name == 'job_watch', f'{name} ended'
    finally:
        errors = {}
        for name, proc in procs.items():
            if proc.poll() is None:
                proc.terminate()
            try:
                errors[name] = proc.communicate(timeout=30)[1]
            except subprocess.TimeoutExpired:
                proc.kill()
                errors[name] = proc.communicate()[1]
    # nothing crashed, and the load held no node up: the lockstep graph ran on without a
    # warning (the trip's ERROR lines are the only lines of the run)
    assert not [n for n, e in errors.items() if 'Traceback' in e], errors
    warnings = {n: [ln for ln in e.splitlines() if '[WARN]' in ln] for n, e in errors.items()}
    assert not any(warnings.values()), warnings
