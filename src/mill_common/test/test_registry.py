"""Registry: the class for a name, one clear refusal, the parameters under each prefix."""

from __future__ import annotations

from typing import ClassVar

import pytest
from mill_common.parameters import ParameterError, ParamSpec, positive
from mill_common.registry import Registry


class _Base:
    PREFIX: ClassVar[str]
    PARAMETERS: ClassVar[tuple[ParamSpec, ...]] = ()


class _Fast(_Base):
    PREFIX = 'fast'
    PARAMETERS = (ParamSpec('gain', 1.0, 'gain [-]', positive),)


class _Slow(_Base):
    PREFIX = 'slow'
    PARAMETERS = (
        ParamSpec('gain', 2.0, 'gain [-]', positive),
        ParamSpec('lag', 0.1, 'lag [s]', positive),
    )


class _Plain(_Base):
    PREFIX = 'plain'


REGISTRY: Registry[_Base] = Registry(
    'mode', {'fast': _Fast, 'slow': _Slow, 'also_slow': _Slow, 'plain': _Plain}
)


def test_names_and_classes_keep_the_registration_order() -> None:
    assert REGISTRY.names() == ('fast', 'slow', 'also_slow', 'plain')
    assert REGISTRY.classes() == (_Fast, _Slow, _Plain)  # a class registered twice: once
    assert REGISTRY.get('also_slow') is _Slow
    assert REGISTRY['fast'] is _Fast
    assert 'plain' in REGISTRY and 'PLAIN' not in REGISTRY
    assert list(REGISTRY) == list(REGISTRY.names()) and len(REGISTRY) == 4


def test_the_name_of_a_class_is_the_first_it_is_registered_under() -> None:
    assert [REGISTRY.name_of(c) for c in (_Fast, _Slow, _Plain)] == ['fast', 'slow', 'plain']
    assert REGISTRY.name_of(_Base) is None


@pytest.mark.parametrize('name', ['FAST', '', 'medium', None, ['fast']])
def test_an_unknown_name_is_refused_naming_the_parameter_and_the_choices(name: object) -> None:
    with pytest.raises(ParameterError) as info:
        REGISTRY.get(name)
    assert info.value.name == 'mode'
    assert str(info.value).endswith('must be one of: fast, slow, also_slow, plain')
    assert REGISTRY.check()(name) == 'must be one of: fast, slow, also_slow, plain'
    assert REGISTRY.check()('slow') is None


def test_parameter_specs_under_each_prefix_once() -> None:
    specs = REGISTRY.parameter_specs()
    assert [n for n, _ in specs] == ['fast.gain', 'slow.gain', 'slow.lag']
    assert dict(specs)['slow.lag'] is _Slow.PARAMETERS[1]  # the class's own spec
    assert not any(s.read_only for _, s in specs)
    frozen = REGISTRY.parameter_specs(read_only=True, exclude=('fast',))
    assert [n for n, _ in frozen] == ['slow.gain', 'slow.lag']
    assert all(s.read_only for _, s in frozen)
    assert [s.default for _, s in frozen] == [2.0, 0.1]


def test_a_class_without_prefix_cannot_be_registered() -> None:
    with pytest.raises(AttributeError):
        Registry('mode', {'base': _Base})
    _Empty = type('_Empty', (_Base,), {'PREFIX': ''})
    with pytest.raises(TypeError, match="mode 'empty'"):
        Registry('mode', {'empty': _Empty})
