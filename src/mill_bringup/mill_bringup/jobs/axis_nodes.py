"""What the lockstep and the realtime three-axis jobs share, as parts both hold. ROS-free.

Neither job inherits from the other: each holds an `AxisNodes` (the graph's nodes, who
sends each topic, the topics the runner keeps) and summarises through `axis_summary`, and
adds what its timing needs (mill_bringup.jobs.axis, .realtime).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from mill_analysis.events import INTRUSIONS, Event, Status, events_of
from mill_analysis.metrics import Window
from mill_analysis.record import RunRecord
from mill_analysis.report.kinds import AxisRecords
from mill_analysis.summary import (
    AxisSummary,
    DepthStretch,
    DriveFigures,
    axis_figures,
    first_stops,
)
from mill_common.signals import AXES
from mill_common.timebase import period_ns, seconds

from mill_bringup.axis_simulation import build_axis_loops
from mill_bringup.bag_handshake import RecordedSteps
from mill_bringup.catalogue import CONTROLLER, FORCE_CONTROLLER, PLANT, TRAJECTORY
from mill_bringup.job_config import JobConfig
from mill_bringup.jobs.base import Ending
from mill_bringup.scenario import Scenario, ScenarioError
from mill_bringup.tuning.prediction_file import compare
from mill_common import topics

JOINT_STATE = 'sensor_msgs/msg/JointState'
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'


class AxisNodes:
    """The nodes of a three-axis graph: one plant (or driver), one trajectory, an observer
    and a controller per axis, perhaps a force controller; the topics the runner keeps of
    them and who must send each."""

    def __init__(self, scen: Scenario, config: JobConfig) -> None:
        plants, trajectories = config.names_of(PLANT), config.names_of(TRAJECTORY)
        if len(plants) != 1 or len(trajectories) != 1:
            raise ScenarioError(
                f'scenario {scen.name}: an axis job has one plant and one trajectory'
            )
        self.config = config
        self.plant, self.trajectory = plants[0], trajectories[0]
        build_axis_loops(config)  # the axes' cores build
        self.dt_ns = period_ns(config.sample_period)
        self.axes = list(config.axes)
        # Who publishes the states: the plant, or the driver the controllers are told of.
        controllers = [n for n in config.nodes if n.kind.per_axis]
        self.state_owner = controllers[0].values['plant_node'] if controllers else self.plant
        forces = config.names_of(FORCE_CONTROLLER)
        if len(forces) > 1:
            raise ScenarioError(f'scenario {scen.name}: more than one force controller')
        self.force_controller = forces[0] if forces else ''

    def monitor_topics(self) -> dict[str, str]:
        """What the runner keeps to build the record."""
        out = {}
        for axis in self.axes:
            out[topics.state(axis)] = JOINT_STATE
            out[topics.estimate(axis)] = JOINT_STATE
            out[topics.joint_command(axis)] = JOINT_STATE
        out[topics.REFERENCE] = JOINT_TRAJECTORY
        out[topics.GROUND_TRUTH] = JOINT_STATE
        if self.force_controller:
            out[topics.FORCE_CONTROL_STATE] = JOINT_STATE
        return out

    def upstream_topics(self) -> list[str]:
        """Topics that must have a publisher before the plant starts."""
        # The monitor cannot see from the plant whether an observer's estimates or a
        # controller's commands reach it: the plant starts once it has matched their publishers.
        out = [topics.estimate(a) for a in self.axes] + [topics.REFERENCE]
        out += [topics.joint_command(a) for a in self.axes]
        return out + ([topics.FEED_OVERRIDE] if self.force_controller else [])

    def bag_handshake(self, scen: Scenario) -> RecordedSteps | None:
        """The recorder's handshake with the plant, if its values (as the job prepared the
        graph) ask for one (recorder_window)."""
        window = scen.parameters(self.plant)['recorder_window']
        if not window:
            return None
        # A step is whole with its states, estimates, commands and cutting force, and the
        # ground truth of the step before if the plant publishes it.
        stepped = {topics.state(a): 0 for a in self.axes}
        for axis in self.axes:
            stepped[topics.estimate(axis)] = 0
            stepped[topics.joint_command(axis)] = 0
        stepped[topics.CUTTING_FORCE] = 0
        if self.config.node(self.plant).values['publish_ground_truth']:
            stepped[topics.GROUND_TRUTH] = 1
        return RecordedSteps(stepped, seconds(self.dt_ns), window)

    def owners(self) -> dict[str, str]:
        """The node each per-axis topic must come from (header.frame_id)."""
        out = {}
        for node in self.config.nodes:
            if not node.kind.per_axis:
                continue
            axis = node.values['axis']
            topic = topics.joint_command(axis) if node.kind.role == CONTROLLER else None
            out[topic or topics.estimate(axis)] = node.name
        # the commands' owners as the drive takes them (its command_owners: x, y, z), where
        # it names them (a benchmark's echo node owns them instead of the controllers)
        drive = next((n for n in self.config.nodes if n.name == self.plant), None)
        named = drive.values.get('command_owners') if drive is not None else None
        for axis, who in zip(AXES, named or (), strict=False):
            if who and axis in self.axes:
                out[topics.joint_command(axis)] = who
        for axis in self.axes:
            out[topics.state(axis)] = self.state_owner
        out[topics.REFERENCE] = self.trajectory
        return out

    def axis_of(self) -> dict[str, str]:
        """The axis of each controller node."""
        return {
            n.name: n.values['axis']
            for n in self.config.nodes
            if n.kind.per_axis and n.kind.role == CONTROLLER
        }

    def events(
        self, statuses: Sequence[Status], start_ns: int = 0, counted_from: int | None = None
    ) -> list[Event]:
        """The machine's events (trips, stops, brakes) of the job's axes."""
        found = events_of(statuses, start_ns, self.axis_of(), counted_from)
        # an intruder is no event of the motion: it makes the record not intact
        return [
            e for e in found if e.kind not in INTRUSIONS and (not e.axis or e.axis in self.axes)
        ]


def axis_summary(
    kind: AxisRecords,
    scen: Scenario,
    rec: RunRecord,
    skip: float,
    failing: Sequence[str],
    ending: Ending | None,
    approach: float = 0.0,
    force_control: Sequence[DepthStretch] | None = None,
    drive: DriveFigures | None = None,
    start_stamp_ns: int | None = None,
) -> AxisSummary:
    """The summary of an axis job's record (its events in it) by its kind of record, with
    the comparison with tune's prediction over the job's window after the approach, and the
    runner's own finding that ended the run, if any."""
    stops = first_stops(rec.events)

    def measured(after: float) -> dict[str, float]:
        figures = axis_figures(rec, Window(approach + after), stops)
        return {m.axis: m.rms_error for m in figures}

    end = float(rec.t[-1]) - approach if len(rec.t) else -1.0
    summary = kind.summarize(
        rec,
        skip,
        approach=approach,
        failing=failing,
        predictions=compare(scen, end, measured) if len(rec.t) else [],
        force_control=force_control,
        drive=drive,
        start_stamp_ns=start_stamp_ns,
    )
    if ending is not None and ending.failure is not None:
        summary = replace(summary, failures=(*summary.failures, ending.failure))
    return summary
