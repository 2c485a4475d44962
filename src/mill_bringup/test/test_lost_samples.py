from mill_bringup.lost_samples import split_lost

OWNERS = {'mill/y/estimate': 'y_observer', 'mill/y/state': 'plant'}


def test_one_sample_per_restart_of_its_sender_is_lost_with_it() -> None:
    missing = {'mill/y/estimate': 1}
    assert split_lost(missing, OWNERS, {'y_observer': 1}) == ({}, {'mill/y/estimate': 1})


def test_more_than_one_per_restart_stays_missing() -> None:
    missing = {'mill/y/estimate': 3}
    still, lost = split_lost(missing, OWNERS, {'y_observer': 2})
    assert still == {'mill/y/estimate': 1} and lost == {'mill/y/estimate': 2}


def test_a_gap_on_a_topic_of_a_node_that_never_died_stays_missing() -> None:
    missing = {'mill/y/state': 1, 'mill/x/estimate': 1}
    still, lost = split_lost(missing, OWNERS, {'y_observer': 1})
    assert still == missing and lost == {}
