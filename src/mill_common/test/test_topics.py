"""Topic names: relative contract names resolved under a machine namespace, as rcl does."""

from __future__ import annotations

import pytest

from mill_common import topics


def test_contract_names_are_relative_and_clock_diagnostics_global() -> None:
    for name in (
        topics.state('x'),
        topics.joint_command('y'),
        topics.estimate('z'),
        topics.controller_state('x'),
        topics.observer_state('x'),
        topics.REFERENCE,
        topics.CUTTING_FORCE,
        topics.CUTTING_FORCE_TRACE,
        topics.FEED_OVERRIDE,
        topics.FORCE_CONTROL_STATE,
        topics.GROUND_TRUTH,
    ):
        assert name.startswith('mill/'), name
    assert (topics.CLOCK, topics.DIAGNOSTICS) == ('/clock', '/diagnostics')


@pytest.mark.parametrize(
    ('text', 'expected'),
    [('', '/'), ('/', '/'), ('machine2', '/machine2'), ('/shop/m_2', '/shop/m_2')],
)
def test_namespace_is_written_as_ros_writes_it(text: str, expected: str) -> None:
    assert topics.namespace(text) == expected


@pytest.mark.parametrize('text', ['2machine', 'a//b', 'a/', 'ma-chine', 'a b', '~a'])
def test_invalid_namespace_is_refused_in_one_line(text: str) -> None:
    with pytest.raises(ValueError, match='is not valid') as info:
        topics.namespace(text)
    assert '\n' not in str(info.value)


def test_qualify_resolves_under_the_namespace_and_keeps_absolute_names() -> None:
    assert topics.qualify(topics.state('x')) == '/mill/x/state'  # today's name
    assert topics.qualify(topics.state('x'), 'machine2') == '/machine2/mill/x/state'
    assert topics.qualify(topics.CLOCK, 'machine2') == '/clock'


def test_the_clock_of_a_machine_is_global_unless_it_has_a_private_one() -> None:
    assert topics.clock() == topics.clock('/', private=True) == '/clock'  # none at the root
    assert topics.clock('machine_a') == '/clock'
    assert topics.clock('machine_a', private=True) == '/machine_a/clock'
    assert topics.clock('/shop/m2', private=True) == '/shop/m2/clock'


def test_namespaces_with_finds_every_machine_of_a_topic() -> None:
    names = [
        '/mill/x/state',
        '/a/mill/x/state',
        '/b/c/mill/x/state',
        '/a/mill/y/state',
        '/xmill/x/state',
    ]
    assert topics.namespaces_with(names, 'mill/x/state') == ['/', '/a', '/b/c']


def test_statuses_belong_to_their_machine() -> None:
    assert topics.machine_id('machine2') == '/machine2'
    assert topics.from_machine('/machine2', '/machine2')
    assert not topics.from_machine('/machine2', '/')
    assert not topics.from_machine('/', 'machine2')
    assert topics.from_machine('mill_plant', 'machine2')  # not a namespace: anyone's


def test_status_names_carry_the_namespace_and_read_back() -> None:
    assert topics.status_name('x_controller', 'inputs') == 'x_controller: inputs'
    a = topics.status_name('x_controller', 'inputs', 'machine_a')
    b = topics.status_name('x_controller', 'inputs', '/machine_b')
    assert (a, b) == ('machine_a/x_controller: inputs', 'machine_b/x_controller: inputs')
    assert topics.status_name('plant', 'x axis', '/shop/m2') == 'shop/m2/plant: x axis'
    for ns in ('/', '/machine_a', '/shop/m2'):
        for node, part in (('x_controller', 'inputs'), ('plant', 'x axis'), ('t', 'a: b')):
            parsed = topics.parse_status_name(topics.status_name(node, part, ns))
            assert parsed == topics.StatusName(ns, node, part)
            assert topics.part_of(topics.status_name(node, part, ns)) == part
            assert topics.status_key(topics.status_name(node, part, ns)) == (node, part)
    assert topics.parse_status_name('plant') == topics.StatusName('/', 'plant', '')
