"""Bumpless replacement of the control law mid-move on the Beltrán x axis (ROS-free)."""

from __future__ import annotations

import copy
import math

import pytest
from mill_common.signals import AxisReference, ControlInputs
from mill_controllers.adaptive_pi import AdaptivePi
from mill_controllers.cascade_pi import CascadePi
from mill_controllers.gpi_controller import GpiController
from mill_controllers.pd_law import AdrcController, PdController
from mill_controllers.switching import BumplessSwitch, check_replacement
from mill_models.axis_data import nominal_input_gain
from mill_observers.gpi import GpiObserver
from mill_plant.axis_plant import AxisPlant
from mill_plant.cutting import StepForce, StepParams
from mill_plant.models.rigid import RigidAxisModel
from mill_trajectory.bezier import BezierParams, BezierRestToRest

T = 1e-3
B = nominal_input_gain('x')
NAN = math.nan
SWITCHES = []
RAW: list[float] = []


def run(new_law, switch_at: float, blend_time: float = 0.05, duration: float = 4.0):
    """Bézier move of x by 10 mm in 3 s under a 20 N cut; adrc, replaced at `switch_at`.

    Returns (commands, old-law outputs at each sample, errors, index of the switch).
    """
    axes = [RigidAxisModel.from_parameters(i, {}) for i in range(3)]  # BELTRAN_TABLE1
    plant = AxisPlant(axes, StepForce(StepParams(force=(20.0, 0.0, 0.0), start_time=0.5)))
    path = BezierRestToRest(
        BezierParams(start=(0.0, 0.0, 0.0), end=(0.01, 0.0, 0.0), t1=0.0, t2=3.0)
    )
    observer = GpiObserver.from_parameters(B, T, {})
    switch = BumplessSwitch(AdrcController.from_parameters(B, T, {}), T, blend_time)
    shadow = None  # the old law, run on alongside to know what it would have done
    raw = None  # a copy of the new law, to know its output without the offset
    commands, shadow_out, errors = [], [], []
    RAW.clear()
    k_switch = round(switch_at / T)
    for k in range(round(duration / T)):
        t = k * T
        y = plant.position[0]
        s = path.sample(t)
        ref = AxisReference(s.position[0], s.velocity[0], s.acceleration[0])
        est = observer.correct(y)
        if k == k_switch:
            shadow = copy.deepcopy(switch.law)
            raw = copy.deepcopy(new_law)
            switch.replace(new_law)
        u = switch.compute(ControlInputs(t, y, ref, est))
        RAW.append(raw.compute(ControlInputs(t, y, ref, est)) if raw else math.nan)
        shadow_out.append(shadow.compute(ControlInputs(t, y, ref, est)) if shadow else u)
        commands.append(u)
        errors.append(ref.position - y)
        observer.predict(u)
        plant.step((u, NAN, NAN), T)
    SWITCHES.append(switch.last_switch)
    return commands, shadow_out, errors, k_switch


def make(name: str):
    return {'gpi': GpiController, 'pd': PdController}[name].from_parameters(B, T, {})


@pytest.mark.parametrize('new', ['gpi', 'pd'])
def test_switch_output_is_the_old_laws_and_the_new_law_takes_over(new: str) -> None:
    u, u_old, e, k = run(make(new), switch_at=1.5)
    # At the switch the command moves exactly as the old law would have moved it.
    assert u[k] == u_old[k]
    # Alone, the new law would have jumped far more than that in the same sample.
    record = SWITCHES[-1]
    assert record.time == pytest.approx(k * T) and record.old_output == u[k]
    assert abs(record.new_output - u[k - 1]) > 10 * abs(u[k] - u[k - 1])
    # Afterwards the output is the new law's: the offset fades with blend_time.
    after = round(0.5 / T)  # 10 blend times later
    assert abs(u[k + after] - u_old[k + after]) > 0.0  # a different law is running
    # The tail error is the new law's own: as if it had run the whole move.
    _, _, e_alone, _ = run(make(new), switch_at=0.0)
    tail = slice(round(3.5 / T), None)
    worst, worst_alone = max(map(abs, e[tail])), max(map(abs, e_alone[tail]))
    assert worst == pytest.approx(worst_alone, rel=0.05, abs=1e-7)


def test_the_offset_decays_with_blend_time() -> None:
    blend = 0.02
    u, _, _, k = run(make('gpi'), switch_at=1.5, blend_time=blend)
    offset = u[k] - RAW[k]
    assert abs(offset) > 1e-3
    for n in (1, 10, 20, 100):
        want = offset * math.exp(-T / blend) ** n
        assert u[k + n] - RAW[k + n] == pytest.approx(want, rel=1e-9, abs=1e-15)


def test_an_identical_law_replaces_without_any_offset() -> None:
    u, u_old, _, k = run(AdrcController.from_parameters(B, T, {}), switch_at=1.5)
    assert u[k] == u_old[k]
    # A fresh ADRC (no internal state) equals the old one: no offset at all.
    assert max(abs(a - b) for a, b in zip(u[k:], u_old[k:], strict=True)) == 0.0


def test_units_must_match() -> None:
    assert check_replacement(AdrcController, GpiController) is None
    assert check_replacement(CascadePi, AdaptivePi) is None
    reason = check_replacement(AdrcController, CascadePi)
    # named by the `controller` value, not by the parameter prefix adrc shares with pd
    assert reason == (
        'cascade_pi commands V but the running adrc commands N·m: '
        'the plant input cannot change unit mid-job'
    )
