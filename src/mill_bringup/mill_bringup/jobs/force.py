"""The cutting-force job of Rubio 2013: force process, force controller, trajectory.

Lockstep per spindle revolution k (t_k the nearest ns to kT): the force process publishes
the force sample F_p(t_k); the force controller answers with the override o_k and its
β-hold slope; the trajectory (`feed_override.lockstep`) answers with the reference of
sample k, whose velocity and acceleration are the feed command and its ramp; the force
process integrates the revolution and publishes the force over it
(/mill/cutting_force/trace). The job is ⌈duration/T⌉ samples; J_c of eq. (14) comes from
the recorded force stream (mill_analysis.force_record).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

from mill_analysis.force_record import FORCE_TOPICS, ForceRecord, continuous_cost
from mill_analysis.force_record import record_from_messages as force_record_from_messages
from mill_analysis.report import kinds
from mill_analysis.summary import ForceSummary
from mill_common.parameters import algorithm_values
from mill_common.timebase import sample_stamp_ns
from mill_controllers.force_control import FORCE_CONTROLLERS, build_law
from mill_controllers.model_reference import ForceControlDesigner, RstDesignParams
from mill_models.force_process import ForceProcessModel

from mill_bringup.bag_handshake import RecordedSteps
from mill_bringup.catalogue import FORCE_CONTROLLER, FORCE_PROCESS, TRAJECTORY, of_role
from mill_bringup.force_loop import ForceLoopSimulation
from mill_bringup.job_config import JobConfig
from mill_bringup.jobs.base import RECORDER_WINDOW, Ending, GraphPlan, Job, MessageSource
from mill_bringup.scenario import LAYOUTS, Scenario, ScenarioError
from mill_bringup.simulation import CoreTimer
from mill_common import topics


def _only(scen: Scenario, role: str) -> str:
    names = [n.name for n in scen.nodes_of(role)]
    if len(names) != 1:
        kind = of_role(role)[0]
        raise ScenarioError(
            f'a force job needs exactly one {kind.package} {kind.executable} node, scenario '
            f'{scen.name} has {len(names)}'
        )
    return names[0]


class ForceJob(Job[ForceRecord]):
    KIND = 'force'
    RECORD = kinds.FORCE
    CLOCK = FORCE_PROCESS

    def __init__(self, scen: Scenario, config: JobConfig | None = None) -> None:
        super().__init__(scen, config)  # every node's parameters valid, the rules kept
        c = self.config
        self.plant = _only(scen, self.CLOCK)
        self.controller = _only(scen, FORCE_CONTROLLER)
        trajectories = scen.nodes_of(TRAJECTORY)
        if len(trajectories) != 1:
            raise ScenarioError('a force job needs exactly one trajectory node')
        self.trajectory = trajectories[0].name
        pv = c.values(self.plant)
        self.controller_values = c.values(self.controller)
        tv = c.values(self.trajectory)
        # The controller's process model is the plant's, and the plant's feed range the
        # controller's: job_config's rules force_model and feed_limits.
        self.model = ForceProcessModel.from_parameters(algorithm_values(ForceProcessModel, pv))
        if not (tv['feed_override.enabled'] and tv['feed_override.lockstep']):
            raise ScenarioError(
                'the trajectory of a force job needs feed_override.enabled and .lockstep'
            )
        # one sample period, a spindle revolution: job_config's rule sample_period
        if not tv['duration'] > 0:
            raise ScenarioError('a force job needs the trajectory duration > 0 [s]')
        self._samples = max(1, math.ceil(tv['duration'] / self.period - 1e-9))
        self.trace_intervals = pv['trace_intervals']
        self.feed_axis = pv['feed_axis']

    @property
    def period(self) -> float:
        return self.model.sample_period

    @property
    def samples(self) -> int:
        return self._samples

    @property
    def sim_time(self) -> float:
        return self._samples * self.period  # the last revolution ends the job

    def design(self) -> ForceControlDesigner:
        """The controller's design; its reference model (ξ, ω_n) is what J_c compares with."""
        kind = self.controller_values['force_controller']
        values = algorithm_values(FORCE_CONTROLLERS[kind], self.controller_values)
        # the design's fields out of the law's (the law's own, e.g. beta, are not needed)
        return ForceControlDesigner(self.model, RstDesignParams.from_node_values(values))

    # -- the distributed run ---------------------------------------------------------------
    def prepare_graph(
        self, monitored: bool, layout: str = LAYOUTS[0], recorded: bool = False
    ) -> None:
        # The force samples need two listeners: the controller and the monitor.
        plant = self.scenario.overrides.setdefault(self.plant, {})
        if monitored:
            plant.setdefault('min_subscribers', 2)
        if monitored:  # the force process waits for the runner too (as AxisJob's plant)
            plant.setdefault('recorder_window', RECORDER_WINDOW)

    def graph_plan(self) -> GraphPlan:
        return GraphPlan(
            upstream=(topics.FEED_OVERRIDE, topics.REFERENCE),
            kept=dict(FORCE_TOPICS),
            recorded={},
            timed=frozenset(),
            late=frozenset(),
            late_after=(),
            steps=self.bag_handshake(),
            sim_time=True,
        )

    def bag_handshake(self) -> RecordedSteps | None:
        window = self.scenario.parameters(self.plant)['recorder_window']
        if not window:
            return None
        # A revolution is whole with its force, the controller's answer to it and its trace,
        # which goes out with the force of the next revolution.
        stepped = {
            topics.CUTTING_FORCE: 0,
            topics.FEED_OVERRIDE: 0,
            topics.FORCE_CONTROL_STATE: 0,
            topics.CUTTING_FORCE_TRACE: 1,
        }
        return RecordedSteps(stepped, self.period, window)

    def progress(self, source: MessageSource) -> float:
        ns = source.latest_stamp_ns(topics.CUTTING_FORCE)
        return ns / 1e9 if ns >= 0 else -math.inf

    def complete(self, source: MessageSource) -> bool:
        # The force after the n-th revolution: every revolution of the job is integrated.
        return source.latest_stamp_ns(topics.CUTTING_FORCE) >= sample_stamp_ns(
            self._samples, self.period
        )

    def settled(self, source: MessageSource) -> bool:
        last = sample_stamp_ns(self._samples - 1, self.period)
        follow = (topics.CUTTING_FORCE_TRACE, topics.FEED_OVERRIDE, topics.FORCE_CONTROL_STATE)
        return all(source.latest_stamp_ns(t) >= last for t in follow)

    def record(self, raw: Mapping[str, Sequence[bytes]]) -> tuple[ForceRecord, dict[str, int]]:
        rec, missing = force_record_from_messages(raw, self._samples, self.period, self.feed_axis)
        design = self.design()
        rec.j_c = continuous_cost(
            rec.trace_ns,
            rec.trace_force,
            self.controller_values['reference_force'],
            design.damping,
            design.omega_n,
        )
        return rec, missing

    # -- offline ---------------------------------------------------------------------------
    def simulation(self, times: CoreTimer | None = None) -> ForceLoopSimulation:
        cv = self.controller_values
        kind = cv['force_controller']
        nominal = cv['nominal_feed']
        law = build_law(
            kind,
            self.model,
            algorithm_values(FORCE_CONTROLLERS[kind], cv),
            cv['override.min'] * nominal,
            cv['override.max'] * nominal,
        )
        loop = {
            'reference_force': cv['reference_force'],
            'job_duration': self._samples * self.period,
            'nominal_feed': nominal,
            'override_min': cv['override.min'],
            'override_max': cv['override.max'],
            'intersample_intervals': self.trace_intervals,
        }
        return ForceLoopSimulation(law, self.model, loop, keep_trace=True)

    # -- results ---------------------------------------------------------------------------
    def summary(self, rec: ForceRecord, skip: float, ending: Ending | None = None) -> ForceSummary:
        summary: ForceSummary = self.RECORD.summarize(rec, skip, events=rec.events)
        if ending is not None and ending.failure is not None:
            summary = replace(summary, failures=(ending.failure,))
        return summary
