"""The plant's parameter table and registries: every piece chosen by name, built from values."""

from __future__ import annotations

import math

import pytest
from mill_common.parameters import ParameterError
from mill_plant.axis_plant import AxisPlant
from mill_plant.config import build_cutting, build_plant, force_process_specs, parameter_specs
from mill_plant.cutting import CuttingForceModel, NoCutting, StepForce
from mill_plant.harmonic_force import HarmonicForce
from mill_plant.kline_force import KlineCuttingForce
from mill_plant.registry import AXIS_MODELS, CUTTING_MODELS

DEFAULTS = {name: spec.default for name, spec in parameter_specs()}
# Changeable at run time: the node's own settings, not the machine's.
NODE_ONLY = {
    'publish_ground_truth',
    'lockstep_timeout',
    'startup_timeout',
    'min_subscribers',
    'excursion',
    'max_hold',
    'speed_limit',
    'hold_deviation',
    'command_report_time',
}


def test_the_table_names_every_parameter_once_and_freezes_the_plant() -> None:
    names = [name for name, _ in parameter_specs()]
    assert len(names) == len(set(names))
    for name, spec in parameter_specs():
        assert spec.name == name
        assert spec.read_only == (name not in NODE_ONLY), name
    for registry in (CUTTING_MODELS, AXIS_MODELS):
        for cls in registry.classes():
            for spec in cls.PARAMETERS:
                if cls.PREFIX != 'rigid':  # the rigid model's keep their plain names
                    assert f'{cls.PREFIX}.{spec.name}' in names
    assert {'mass', 'pitch', 'coulomb_friction'} <= set(names)
    assert 'rigid.mass' not in names


@pytest.mark.parametrize(
    ('name', 'cls'),
    [
        ('kline', KlineCuttingForce),
        ('step', StepForce),
        ('harmonic', HarmonicForce),
        ('none', NoCutting),
    ],
)
def test_cutting_models_are_built_by_name(name: str, cls: type[CuttingForceModel]) -> None:
    assert CUTTING_MODELS.get(name) is cls
    assert name == cls.PREFIX
    force = build_cutting({**DEFAULTS, 'cutting_model': name})
    assert type(force) is cls


def test_cutting_values_reach_the_model_in_its_units() -> None:
    values = {**DEFAULTS, 'kline.helix_angle': 30.0, 'kline.spindle_speed': 3000.0}
    kline = build_cutting(values)
    assert isinstance(kline, KlineCuttingForce)
    assert kline.helix_angle == math.radians(30.0)  # degrees on the node, radians inside
    assert kline.spindle_speed_rpm == 3000.0
    step = build_cutting({**DEFAULTS, 'cutting_model': 'step', 'step.start_time': 0.25})
    assert step.force(0.2, (0, 0, 0), (0, 0, 0)) == (0.0, 0.0, 0.0)
    assert step.force(0.25, (0, 0, 0), (0, 0, 0)) == (0.0, 100.0, 0.0)


def test_an_unknown_cutting_model_is_refused_by_name() -> None:
    spec = dict(parameter_specs())['cutting_model']
    assert spec.check('chatter') == 'must be one of: kline, step, harmonic, load, none'
    with pytest.raises(ParameterError) as info:
        build_cutting({**DEFAULTS, 'cutting_model': 'chatter'})
    assert info.value.name == 'cutting_model'


def test_a_bad_cutting_value_names_its_full_parameter() -> None:
    with pytest.raises(ParameterError) as info:
        build_cutting({**DEFAULTS, 'cutting_model': 'harmonic', 'harmonic.teeth': 0})
    assert info.value.name == 'harmonic.teeth'


def test_axis_models_come_from_their_registry() -> None:
    values = {**DEFAULTS, 'axis_model': ['rigid', 'flexible', 'velocity_drive']}
    plant = build_plant(values)
    assert isinstance(plant, AxisPlant)
    assert [type(m) for m in plant.models] == [AXIS_MODELS.get(n) for n in values['axis_model']]


def test_the_force_process_node_shares_the_lockstep_timeouts() -> None:
    ours = dict(force_process_specs())
    plant = dict(parameter_specs())
    assert ours['lockstep_timeout'] is plant['lockstep_timeout']
    assert ours['startup_timeout'] is plant['startup_timeout']
    assert ours['min_subscribers'].default == 1  # the force controller only
    assert all(s.read_only for n, s in ours.items() if n.startswith('force_process.'))


def test_the_simulated_machine_takes_each_input_unit_from_its_axis_model() -> None:
    from mill_plant.simulated_machine import SimulatedMachine

    values = {**DEFAULTS, 'axis_model': ['transfer_function', 'velocity_drive', 'flexible']}
    machine = SimulatedMachine({**values, 'axes': ['x', 'y', 'z']})
    assert machine.input_units() == {'x': 'V', 'y': 'V', 'z': 'N·m'}
    for model, unit in zip(machine.plant.models, machine.input_units().values(), strict=True):
        assert unit == type(model).INPUT_UNIT
    assert SimulatedMachine({**DEFAULTS, 'axes': ['y']}).input_units() == {'y': 'N·m'}


def test_the_drive_command_delay_is_bounded_as_the_axis_nodes_compensate() -> None:
    # Issue 37: command_delay had no bound; the drive fills a line of N commands per axis
    # at start, so 10^9 ran it out of memory. The bound is the controllers' and
    # observers' own (they compensate N, and their command_delay must equal the drive's).
    from mill_common.node_params import AxisNodeParams
    from mill_common.parameters import validate

    spec = dict(parameter_specs())['command_delay']
    axis_node = dict(AxisNodeParams.named_specs())['command_delay']
    assert spec.check.bounds == axis_node.check.bounds == (0, 1000)  # type: ignore[attr-defined]
    assert validate(spec, 1000) == 1000
    with pytest.raises(ParameterError) as info:
        validate(spec, 10**9)
    assert str(info.value) == (
        'invalid parameter command_delay=1000000000: must be a whole number in [0, 1000]'
    )
