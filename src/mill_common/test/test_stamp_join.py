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
