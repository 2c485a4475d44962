"""Bags of another writer (rosbags, MCAP and sqlite3) give the RunRecord of the offline
simulator; the record built in two processes is the one built in one."""

from __future__ import annotations

import numpy as np
import pytest
from mill_bag.reader import open_bag
from mill_bringup.metrics import SIGNALS, summarize
from mill_bringup.run_record import read_run, record_from_raw, record_topics
from mill_common.signals import AXES


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_bag_of_another_writer_gives_the_offline_record(foreign_bag, storage) -> None:
    path, rec = foreign_bag(storage)
    run = read_run(path)
    assert (run.n, run.dt_ns, run.axes) == (rec.t.size, 1_000_000, ['x', 'y', 'z'])
    assert run.missing == {}
    np.testing.assert_array_equal(run.record.t, rec.t)
    for name in SIGNALS:
        np.testing.assert_array_equal(run.record[name], rec[name], err_msg=name)
    assert summarize(run.record, 0.1) == summarize(rec, 0.1)
    assert run.feed_override is None
    if storage == 'mcap':  # rosbags writes publish time = log time = the receive time
        assert run.state_wall_ns is not None and run.state_wall_ns[1] - run.state_wall_ns[0] > 0


def test_record_built_in_two_processes_equals_one(foreign_bag) -> None:
    path, _ = foreign_bag('mcap')
    raw: dict[str, list[bytes]] = {}
    for topic, _type, _log, _pub, data in open_bag(path).read():
        raw.setdefault(topic, []).append(data)
    types = record_topics(AXES)
    raw = {t: raw[t] for t in types}
    one, missing_one = record_from_raw(raw, types, AXES, 401, 1_000_000, workers=1)
    two, missing_two = record_from_raw(raw, types, AXES, 401, 1_000_000, workers=2)
    assert missing_one == missing_two == dict.fromkeys(missing_one, 0)
    assert len(missing_one) == 3 * 3 + 2  # every listened per-sample topic
    for name in SIGNALS:
        np.testing.assert_array_equal(one[name], two[name], err_msg=name)
        assert np.isfinite(one[name]).any(), name
