"""build_check: the one line a failed build gives, and which other choices a change touches."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest
from mill_common.build_check import BUILD_ERRORS, build_failure, changed_choices
from mill_common.parameters import ParameterError, ParamSpec, positive
from mill_common.registry import Registry


def _raised(f) -> BaseException:
    with pytest.raises(BUILD_ERRORS) as info:
        f()
    return info.value


def test_a_failure_is_one_line_with_its_kind_unless_it_is_a_checks_own_message() -> None:
    assert build_failure(_raised(lambda: 1e300**2)) == (
        "OverflowError: (34, 'Numerical result out of range')"
    )
    assert build_failure(_raised(lambda: np.linalg.solve(np.zeros((2, 2)), np.ones(2)))) == (
        'LinAlgError: Singular matrix'
    )
    with np.errstate(divide='raise'):
        assert build_failure(_raised(lambda: np.float64(1.0) / 0.0)) == (
            'FloatingPointError: divide by zero encountered in scalar divide'
        )
    assert build_failure(_raised(lambda: 1 / 0)) == 'ZeroDivisionError: division by zero'
    assert build_failure(ValueError('gpi needs\n  the model')) == 'gpi needs the model'
    assert build_failure(ParameterError('a', -1, 'must be > 0')) == (
        'invalid parameter a=-1: must be > 0'
    )
    assert build_failure(ValueError()) == 'ValueError'


class _Law:
    PREFIX: ClassVar[str] = ''
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = ()


class _Fast(_Law):
    PREFIX = 'fast'
    PARAMETERS = (ParamSpec('gain', 1.0, 'gain [-]', positive),)


class _Slow(_Law):
    PREFIX = 'slow'
    PARAMETERS = (ParamSpec('lag', 0.1, 'lag [s]', positive),)


LAWS: Registry[_Law] = Registry('law', {'fast': _Fast, 'slow': _Slow, 'also_slow': _Slow})


def test_the_choices_whose_parameters_change_other_than_the_selected_one() -> None:
    old = {'law': 'fast', 'fast.gain': 1.0, 'slow.lag': 0.1}
    assert changed_choices(LAWS, {**old, 'slow.lag': 0.2}, old) == ['slow']  # once per class
    assert changed_choices(LAWS, {**old, 'fast.gain': 2.0}, old) == []  # the selected one
    assert changed_choices(LAWS, {**old, 'law': 'slow', 'fast.gain': 2.0}, old) == ['fast']
    assert changed_choices(LAWS, dict(old), old) == []
    assert changed_choices(LAWS, {**old, 'slow.lag': math.inf}, old) == ['slow']
