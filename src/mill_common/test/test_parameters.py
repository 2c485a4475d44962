"""Parameter specs: checks that describe themselves, types, and the descriptors nodes declare."""

from __future__ import annotations

import math

import pytest
from mill_common.parameters import (
    ParameterError,
    ParamSpec,
    StringList,
    UnknownParameterError,
    in_range,
    non_negative,
    number,
    number_list,
    one_of,
    positive,
    positive_int,
    positive_or_inf,
    type_of,
    validate,
    value_type,
)


@pytest.mark.parametrize(
    ('check', 'value', 'reason'),
    [
        (positive, 0.0, 'must be > 0'),
        (positive, -1, 'must be > 0'),
        (positive, math.nan, 'must be a finite number'),
        (positive, math.inf, 'must be a finite number'),
        (positive_or_inf, math.inf, None),
        (positive_or_inf, 0.0, 'must be > 0'),
        (non_negative, 0.0, None),
        (non_negative, -1e-12, 'must be >= 0'),
        (in_range(1e-6, 1.0), 2.0, 'must be in [1e-06, 1.0]'),
        (in_range(1e-6, 1.0), 1.0, None),
        (positive_int, 0, 'must be a whole number >= 1'),
        (positive_int, True, 'must be a whole number >= 1'),
        (positive_int, 3, None),
        (one_of('pd', 'adrc'), 'pid', 'must be one of: pd, adrc'),
        (number_list(3, positive), [1.0, 0.0, 2.0], 'entry 1 must be > 0'),
        (number_list(3), [1.0, 2.0], 'must have 3 entries, got 2'),
        (StringList('topic names'), ['/a', 3], 'must be a list of topic names'),
        (number, True, 'must be a finite number'),
    ],
)
def test_checks_refuse_with_their_reason(check, value, reason) -> None:
    assert check(value) == reason


def test_checks_describe_themselves() -> None:
    assert (positive.text, positive.bounds, positive.low_open) == ('> 0', (0, math.inf), True)
    assert (non_negative.text, non_negative.bounds) == ('>= 0', (0, math.inf))
    assert positive_or_inf.text == '> 0, or .inf (no limit)'
    assert (in_range(0, 89).text, in_range(0, 89).bounds) == ('in [0, 89]', (0, 89))
    assert (positive_int.text, positive_int.bounds) == ('a whole number >= 1', (1, math.inf))
    assert one_of('a', 'b').text == 'one of: a, b'
    assert one_of('a', 'b').bounds is None
    assert number_list(3, positive).text == 'a list of 3 numbers, each > 0'
    assert number_list(3).text == 'a list of 3 numbers'


def test_types_come_from_the_default_or_the_check() -> None:
    assert value_type(ParamSpec('a', 1.0, '')) == 'double'
    assert value_type(ParamSpec('a', 4, '')) == 'integer'
    assert value_type(ParamSpec('a', True, '')) == 'bool'
    assert value_type(ParamSpec('a', 'x', '')) == 'string'
    assert value_type(ParamSpec('a', [1.0, 2.0], '')) == 'double_array'
    assert value_type(ParamSpec('a', ['x'], '')) == 'string_array'
    assert value_type(ParamSpec('a', [], '', StringList())) == 'string_array'
    with pytest.raises(ValueError, match='cannot tell its type'):
        value_type(ParamSpec('a', [], ''))
    assert type_of([1, 2.0]) == 'mixed list'
    assert type_of(None) == 'null'


def test_a_value_of_the_wrong_type_is_refused_naming_the_expected_type() -> None:
    spec = ParamSpec('omega_c', 12.0, 'ω', positive)
    with pytest.raises(ParameterError) as caught:
        validate(spec, 'abc', 'pd.omega_c')
    assert str(caught.value) == (
        "invalid parameter pd.omega_c='abc': "
        'must be of type double (a floating-point number), got string'
    )
    with pytest.raises(ParameterError, match=r'must be of type integer .*, got double'):
        validate(ParamSpec('substeps', 4, '', positive_int), 4.0)
    with pytest.raises(ParameterError, match=r'must be of type bool .*, got integer'):
        validate(ParamSpec('gravity', False, ''), 1)
    # A list's own check names the entry; the type speaks where the check has nothing to say.
    with pytest.raises(ParameterError, match='entry 0 must be a finite number'):
        validate(ParamSpec('mass', [1.0, 2.0, 3.0], '', number_list(3)), ['a', 'b', 'c'])
    with pytest.raises(ParameterError, match=r'type double_array .*, got string_array'):
        validate(ParamSpec('free', [1.0], ''), ['a'])


def test_integers_are_taken_for_doubles() -> None:
    spec = ParamSpec('omega_c', 12.0, 'ω', positive)
    value = validate(spec, 20)
    assert value == 20.0 and isinstance(value, float)
    values = validate(ParamSpec('mass', [1.0, 2.0], '', number_list(2)), [3, 4])
    assert values == [3.0, 4.0] and all(isinstance(v, float) for v in values)
    assert validate(ParamSpec('topics', [], '', StringList()), []) == []


def test_unknown_names_are_named_with_the_closest_known_one() -> None:
    error = UnknownParameterError({'pd.omega': 20.0}, ['pd.omega_c', 'pd.zeta_c'], '/x')
    assert str(error) == (
        'unknown parameter pd.omega=20.0 (did you mean pd.omega_c?): /x has no such parameter'
    )
    error = UnknownParameterError({'b': 1, 'a': 'x'}, ['pd.omega_c'], '/x')
    assert str(error) == "unknown parameters a='x', b=1: /x has no such parameters"
    assert isinstance(error, ValueError) and error.names == ['a', 'b']


def test_descriptors_carry_type_range_and_constraint() -> None:
    from mill_common.ros_params import INT64_MAX, descriptor
    from rcl_interfaces.msg import ParameterType

    d = descriptor(ParamSpec('omega_c', 12.0, 'ω_c [rad/s]', positive))
    assert (d.type, d.description, d.additional_constraints) == (
        ParameterType.PARAMETER_DOUBLE,
        'ω_c [rad/s]',
        '> 0',
    )
    assert not d.dynamic_typing and not d.read_only
    (r,) = d.floating_point_range
    assert (r.from_value, r.to_value, r.step) == (0.0, math.inf, 0.0)
    assert not d.integer_range

    d = descriptor(ParamSpec('taps', 2, 'taps', positive_int, read_only=True))
    (r,) = d.integer_range
    assert (r.from_value, r.to_value, r.step) == (1, INT64_MAX, 1)
    assert d.type == ParameterType.PARAMETER_INTEGER and d.read_only

    d = descriptor(ParamSpec('period', 0.001, 'T', in_range(1e-6, 1.0)))
    (r,) = d.floating_point_range
    assert (r.from_value, r.to_value) == (1e-6, 1.0)

    d = descriptor(ParamSpec('law', 'pd', 'law', one_of('pd', 'adrc')))
    assert d.type == ParameterType.PARAMETER_STRING
    assert d.additional_constraints == 'one of: pd, adrc'
    assert not d.floating_point_range and not d.integer_range

    d = descriptor(ParamSpec('mass', [1.0, 2.0, 3.0], 'm', number_list(3, positive)))
    assert d.type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert d.additional_constraints == 'a list of 3 numbers, each > 0'
    assert not d.floating_point_range  # ROS ranges are for single numbers

    d = descriptor(ParamSpec('topics', [], 'topics', StringList('topic names')))
    assert d.type == ParameterType.PARAMETER_STRING_ARRAY

    d = descriptor(ParamSpec('custom', 1.0, 'c', lambda v: None))
    assert d.type == ParameterType.PARAMETER_DOUBLE and d.additional_constraints == ''


def test_a_refused_value_is_shown_short_however_long_it_is() -> None:
    from mill_common.parameters import ParameterError, shown, unknown_parameters_message

    assert shown([1.0, 2.0]) == '[1.0, 2.0]'
    long = [0.5] * 1_000_000  # a list a parameter file of a few MB could give
    text = str(ParameterError('harmonic.harmonics', long, 'must list at most 32 harmonics'))
    assert len(text) < 320 and '\n' not in text
    assert text.startswith('invalid parameter harmonic.harmonics=[0.5, 0.5, ')
    assert text.endswith('... (4999800 more characters): must list at most 32 harmonics')
    unknown = unknown_parameters_message({'pd.omega': 'x' * 10_000}, ['pd.omega_c'], '/x')
    assert len(unknown) < 320 and 'did you mean pd.omega_c?' in unknown
