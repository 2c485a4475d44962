"""Cutting-force control by adaptive feed (Rubio 2013), ROS-free: choice, parameters, one sample.

The `force_controller` parameter picks the law (registry below); `ForceFeedLoop` turns one
force sample into the feed override of that sample, the same way in the force-controller
node and in the offline loop (mill_bringup.force_loop):

1. a non-finite force sample is replaced by the last finite one (counted as held);
2. the law gets the depth of cut a_dc and returns the feed command f_c,k [mm/s]: the known
   a_dc(t_k) of the time profile (`depth_source: profile`, Rubio 2013), or the depth of the
   tool below the workpiece top at that sample (`depth_source: position`: the measured z,
   a_dc = workpiece_top − z; where the tool is not below the top the law keeps the last
   depth, it cannot be designed for none);
3. the override o_k = f_c,k / nominal_feed is clamped to [override_min, override_max]; a
   non-finite one holds the last override; the law is told the feed actually applied;
4. the β-hold of the active β gives the override's slope over the sample,
   ȯ = β(o_k − o_{k−1})/T, so the path speed follows u_k + β(u_k − u_{k−1})τ/T.

`ForceSampler` decides which force samples are control instants (the first sample at or after
each j·T, T one spindle revolution of the model) and which force the law gets there (the
peak |force| of the samples since the last instant, or the sample itself), for the node and
the offline axis job alike.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, ClassVar, Protocol

from mill_common.declared import ParamSet, param
from mill_common.node_params import input_watch_specs
from mill_common.parameters import ParamSpec, algorithm_values, number, one_of, positive
from mill_common.registry import Registry
from mill_common.timebase import sample_index, sample_stamp_ns
from mill_models.force_process import ForceProcessModel
from mill_models.holds import SampleHold, hold_input

from mill_controllers.model_reference import ForceControlDesigner, ModelReferenceForceController
from mill_controllers.multi_model import MultiModelScheme1, MultiModelScheme2


class ForceLaw(Protocol):
    designer: ForceControlDesigner  # its reference model eq. (7) is what J_c compares with

    @property
    def active_beta(self) -> float: ...

    def set_depth(self, depth: float) -> None: ...

    def update(self, force_reference: float, force_measured: float) -> float: ...

    def record_applied(self, feed: float) -> None: ...


class RegisteredForceLaw(ForceLaw, Protocol):
    """A force law the force_controller parameter chooses: parameters and a factory."""

    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]]

    @classmethod
    def from_parameters(
        cls,
        model: ForceProcessModel,
        values: Mapping[str, Any],
        feed_min: float = ...,
        feed_max: float = ...,
    ) -> ForceLaw:
        """The law from its values (names without prefix) and the feed range [mm/s]."""
        ...


# The force_controller parameter value -> class (one file per algorithm).
FORCE_CONTROLLERS: Registry[RegisteredForceLaw] = Registry(
    'force_controller',
    {
        'fixed': ModelReferenceForceController,  # Rubio 2013 fig. 1, eq. (4)-(11), one β
        'scheme1': MultiModelScheme1,  # Rubio 2013 §3.2.1, eq. (13)
        'scheme2': MultiModelScheme2,  # Rubio 2013 §3.2.2
    },
)
FORCE_COMPONENTS = ('resultant', 'x', 'y', 'z')
DEPTH_SOURCES = ('profile', 'position')


def _override_bound(value: Any) -> str | None:
    if not isinstance(value, int | float) or isinstance(value, bool) or not 0 <= value <= 10:
        return 'must be a number in [0, 10]'
    return None


@dataclass(frozen=True)
class ForceNodeParams(ParamSet):
    """The force controller node's own parameters (beside the input watch, the process
    model and the laws')."""

    force_controller: str = param(
        'fixed',
        'force law: fixed (one β), scheme1 or scheme2 (Rubio 2013 multi-model)',
        FORCE_CONTROLLERS.check(),
        read_only=True,
    )
    reference_force: float = param(1200.0, 'reference peak force F_r', positive, unit='N')
    nominal_feed: float = param(
        10.0,
        'programmed feed of the path [mm/s]: override 1 means this feed',
        positive,
        read_only=True,
    )
    force_component: str = param(
        'resultant',
        'what of /mill/cutting_force is the controlled force: the resultant |F| or one component',
        one_of(*FORCE_COMPONENTS),
        read_only=True,
    )
    force_measure: str = param(
        'peak',
        'force the law gets at a control instant: the peak |force| of the samples '
        'heard since the last instant (Rubio 2013 F_p: the peak force of each '
        'revolution), or the sample at the instant',
        one_of('peak', 'sample'),
        read_only=True,
    )
    depth_source: str = param(
        'profile',
        'depth of cut the law is told: profile = force_process.depth_profile at the '
        'control instant (Rubio 2013: a known function of time); position = the '
        "tool's depth below workpiece_top, from the measured z (/mill/z/state)",
        one_of(*DEPTH_SOURCES),
        read_only=True,
    )
    workpiece_top: float = param(
        0.0,
        'z of the workpiece top surface [m] (depth_source position: a_dc = top − z)',
        number,
        read_only=True,
    )


@dataclass(frozen=True)
class OverrideRange(ParamSet):
    """The range of the feed override sent (override.min, override.max)."""

    PREFIX: ClassVar[str] = 'override'
    min: float = param(
        0.0, 'smallest feed override sent', _override_bound, unit='-', read_only=True
    )
    max: float = param(2.0, 'largest feed override sent', _override_bound, unit='-', read_only=True)


def parameter_specs() -> list[tuple[str, ParamSpec]]:
    specs = [*ForceNodeParams.named_specs(), *OverrideRange.named_specs(), *input_watch_specs()]
    # The process model and the law's design are built once (read-only): a law's memory
    # belongs to its design, so a new design means a new node.
    model = [
        (f'{ForceProcessModel.PREFIX}.{s.name}', replace(s, read_only=True))
        for s in ForceProcessModel.PARAMETERS
    ]
    return specs + model + FORCE_CONTROLLERS.parameter_specs(read_only=True)


def build_model(values: Mapping[str, Any]) -> ForceProcessModel:
    return ForceProcessModel.from_parameters(algorithm_values(ForceProcessModel, values))


def build_law(
    kind: str, model: ForceProcessModel, values: Mapping[str, Any], feed_min: float, feed_max: float
) -> ForceLaw:
    """The law `kind` with its own values (names without prefix) and the feed range [mm/s]."""
    return FORCE_CONTROLLERS.get(kind).from_parameters(model, values, feed_min, feed_max)


@dataclass(frozen=True)
class OverrideCommand:
    """The override of one sample and how it came about."""

    override: float  # o_k, in range [-]
    slope: float  # ȯ over the sample from the β-hold [1/s]
    feed_command: float  # the law's f_c,k [mm/s] (before the clamp)
    beta: float  # active β over the sample
    force: float  # the force the law used [N] (the last finite one)
    held: bool  # the force sample was not finite
    clamped: bool  # the law's override was outside the range or not finite
    depth: float = math.nan  # the depth of cut the law was told [mm]


class ForceFeedLoop:
    """One force sample in, one feed override (value and β-hold slope) out."""

    def __init__(
        self,
        law: ForceLaw,
        model: ForceProcessModel,
        nominal_feed: float,
        override_min: float,
        override_max: float,
    ) -> None:
        if not override_min <= override_max:
            raise ValueError(f'override range [{override_min}, {override_max}] is empty')
        self.law = law
        self.model = model
        self.T = model.sample_period
        self.nominal_feed = float(nominal_feed)
        self.lo = float(override_min)
        self.hi = float(override_max)
        self._hold = SampleHold(0.0)
        self._last = 0.0  # the override before the first sample: at rest
        self._depth = model.depth_at(0.0)  # told when the tool is not below the top

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> ForceFeedLoop:
        model = build_model(values)
        node = ForceNodeParams.from_node_values(values)
        kind, nominal = node.force_controller, node.nominal_feed
        bounds = OverrideRange.from_node_values(values)
        own = algorithm_values(FORCE_CONTROLLERS[kind], values)
        law = build_law(kind, model, own, bounds.min * nominal, bounds.max * nominal)
        return cls(law, model, nominal, bounds.min, bounds.max)

    @property
    def held_samples(self) -> int:
        return self._hold.held

    def step(
        self, t: float, reference: float, measured: float, depth: float | None = None
    ) -> OverrideCommand:
        """One control instant at time t [s]; depth [mm]: the tool's (None: the profile's)."""
        y = self._hold(measured)
        held = not math.isfinite(measured)
        if depth is None:
            self._depth = self.model.depth_at(t)  # the depth is known (Rubio 2013 §2)
        elif depth > 0.0:
            self._depth = depth
        self.law.set_depth(self._depth)
        u = self.law.update(reference, y)
        wanted = u / self.nominal_feed
        override = min(self.hi, max(self.lo, wanted)) if math.isfinite(wanted) else self._last
        self.law.record_applied(override * self.nominal_feed)
        beta = self.law.active_beta
        _, slope = hold_input(override, self._last, beta, self.T)
        self._last = override
        return OverrideCommand(override, slope, u, beta, y, held, override != wanted, self._depth)


def tool_depth(workpiece_top: float, z: float) -> float:
    """Depth of the tool below the workpiece top [mm] from z [m] (≤ 0: not cutting)."""
    return (workpiece_top - z) * 1e3


class ForceSampler:
    """Control instants on a stream of force samples, and the force the law gets at each."""

    def __init__(self, period: float, component: str, measure: str) -> None:
        if component not in FORCE_COMPONENTS or measure not in ('peak', 'sample'):
            raise ValueError(f'force component {component!r} or measure {measure!r} unknown')
        self.T = float(period)
        self._axis = FORCE_COMPONENTS.index(component) - 1  # -1: the resultant
        self._peak_mode = measure == 'peak'
        self._next = 0  # the next control instant
        self._peak = -0.0  # the largest |force| heard since the last control instant

    @property
    def next_instant(self) -> int:
        """The index j of the next control instant."""
        return self._next

    def value(self, force: tuple[float, float, float]) -> float:
        """The controlled quantity of one force sample [N]."""
        if self._axis < 0:
            fx, fy, fz = force
            return math.sqrt(fx * fx + fy * fy + fz * fz)
        return float(force[self._axis])

    def offer(self, ns: int, force: tuple[float, float, float]) -> tuple[int, float] | None:
        """The next force sample (stamp ns, in order): (j, force for the law) if it is the
        first sample at or after control instant j, else None."""
        value = self.value(force)
        if math.isfinite(self._peak) and (math.isnan(value) or abs(value) > abs(self._peak)):
            self._peak = value  # a NaN in the window stays: the law holds the last force
        if ns < sample_stamp_ns(self._next, self.T):
            return None  # between control instants
        j = sample_index(ns, self.T)
        measured = self._peak if self._peak_mode else value
        self._peak = -0.0
        self._next = j + 1
        return j, measured
