"""Message types: their names, rosbags' typestore, definitions, RIHS01 hashes, decoding CDR.

The typestore holds the ROS 2 Jazzy types rosbags ships; a type it lacks is loaded
from its installed .msg file (the ament index, where rosbag2 finds definitions),
with the types its fields refer to. Bags carry each topic's definition (MCAP schema,
ros2msg) and RIHS01 type hash, both from `message_definition`.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mill_bag.cdr import joint_state_cdr
from mill_bag.errors import BagError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

JOINT_STATE = 'sensor_msgs/msg/JointState'
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'
CLOCK = 'rosgraph_msgs/msg/Clock'
DIAGNOSTIC_ARRAY = 'diagnostic_msgs/msg/DiagnosticArray'
DURATION = 'builtin_interfaces/msg/Duration'
TIME = 'builtin_interfaces/msg/Time'
HEADER = 'std_msgs/msg/Header'
FLOAT64 = 'std_msgs/msg/Float64'
STRING = 'std_msgs/msg/String'


@lru_cache(maxsize=1)
def typestore() -> Typestore:
    """rosbags' store of the ROS 2 Jazzy message types (more are added from share/*/msg)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _msg_file(msgtype: str) -> Path | None:
    """The installed .msg file of a type, where rosbag2 finds definitions (ament index)."""
    pkg, _, name = msgtype.partition('/msg/')
    try:
        from ament_index_python.packages import get_package_share_directory

        path = Path(get_package_share_directory(pkg)) / 'msg' / f'{name}.msg'
    except Exception:
        path = Path(sys.prefix) / 'share' / pkg / 'msg' / f'{name}.msg'
    return path if path.is_file() else None


def _field_types(fields: Iterable[tuple[str, Any]]) -> Iterator[str]:
    """Names of the message types a type's fields refer to (rosbags field definitions)."""
    for _name, (kind, detail) in fields:
        if kind.name in ('ARRAY', 'SEQUENCE'):
            kind, detail = detail[0]
        if kind.name == 'NAME':
            yield detail


def ensure_type(msgtype: str) -> None:
    """Make `msgtype` known to the typestore, loading its .msg files if Jazzy's store lacks it."""
    store = typestore()
    pending = [msgtype]
    loaded: set[str] = set()
    while pending:
        name = pending.pop()
        if name in store.fielddefs or name in loaded:
            continue
        path = _msg_file(name)
        if path is None:
            raise BagError(f'no message definition for {name}')
        from rosbags.typesys import get_types_from_msg

        types = get_types_from_msg(path.read_text(), name)
        store.register(types)
        loaded.add(name)
        for _consts, fields in types.values():
            pending.extend(t for t in _field_types(fields) if t not in store.fielddefs)


def message_definition(msgtype: str) -> tuple[str, str]:
    """(ros2msg definition with its dependencies, RIHS01 type hash) of a type."""
    ensure_type(msgtype)
    store = typestore()
    msgdef, _ = store.generate_msgdef(msgtype, ros_version=2)
    return msgdef, store.hash_rihs01(msgtype)


def sim_stamped(msgtype: str) -> bool:
    """True if the message carries a stamp of the graph's clock: a std_msgs/Header first, or Clock.

    Other builtin_interfaces/Time stamps (rcl_interfaces/Log, ParameterEvent) are wall
    time and are not used as sim time.
    """
    if msgtype == CLOCK:
        return True
    try:
        ensure_type(msgtype)
    except BagError:
        return False
    fields = typestore().fielddefs[msgtype][1]
    return bool(fields) and fields[0][1][1] == HEADER


def decode(msgtype: str, data: bytes) -> Any:
    """A CDR message as an object with the message's field names (as rclpy's).

    sensor_msgs/JointState, most messages of a joint control loop, is read by `joint_state_cdr`
    (4x faster); everything else, and any JointState it does not accept, by rosbags. Bytes
    that are no such message (any node may publish anything) raise BagError, in one line.
    """
    if msgtype == JOINT_STATE:
        msg = joint_state_cdr(data)
        if msg is not None:
            return msg
    try:
        return typestore().deserialize_cdr(data, msgtype)
    except Exception as exc:  # rosbags' SerdeError, KeyError for an unknown type, ...
        raise BagError(f'{len(data)} bytes that are no {msgtype}: {exc}') from None
