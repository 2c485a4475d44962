from mill_common.stamp_join import StampJoin


def test_completes_in_any_order_and_prunes_older():
    join = StampJoin(('a', 'b'))
    assert join.put('a', 1, 'a1') is None
    assert join.put('b', 2, 'b2') is None
    assert join.put('a', 2, 'a2') == {'a': 'a2', 'b': 'b2'}
    # stamp 1 can no longer complete and has been dropped
    assert join.oldest_incomplete() is None


def test_reports_missing_slot():
    join = StampJoin(('state', 'estimate', 'reference'))
    join.put('state', 5, 0.0)
    join.put('reference', 5, 0.0)
    assert join.oldest_incomplete() == (5, ['estimate'])


def test_optional_slot_is_handed_over_and_can_become_required():
    join = StampJoin(('a', 'b'))
    join.put('m', 1, 'm1')
    join.put('a', 1, 'a1')
    assert join.put('b', 1, 'b1') == {'a': 'a1', 'b': 'b1', 'm': 'm1'}
    join.put('a', 2, 'a2')
    join.put('b', 3, 'b3')
    assert join.require(('a', 'b', 'm')) is None  # nothing is complete yet
    assert join.put('b', 2, 'b2') is None  # now waits for m
    assert join.oldest_incomplete() == (2, ['m'])
    assert join.put('m', 2, 'm2') == {'a': 'a2', 'b': 'b2', 'm': 'm2'}
    # Dropping a requirement completes a waiting sample at once.
    join.put('a', 3, 'a3')
    assert join.require(('a', 'b')) == (3, {'a': 'a3', 'b': 'b3'})
