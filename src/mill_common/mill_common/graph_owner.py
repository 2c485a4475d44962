"""Who sent a message, as the ROS graph identifies it: its publisher's GID. ROS side.

header.frame_id is what a sender says of itself: any publisher can write the owner's name
there. What no publisher inside the domain can choose is the GID of its endpoint: DDS gives
it (participant prefix + entity id), every message arrives with it, and the graph lists
each publisher endpoint with its GID, node name and namespace. So a receiver:

- takes an owned input with `GidSubscription`: the serialized bytes and the publisher GID
  of each message (rclpy's own take drops the GID: its MessageInfo in Jazzy has only the
  timestamps and sequence numbers, so the take is rcl's, called through ctypes, inside a
  Waitable that every rclpy executor runs: the C++ EventsExecutor calls a subscription
  handle's take in C++, past any Python override);
- asks `GraphOwners.verdict(topic, gid)`: a `mill_common.checks.Sender` (OWNER, FOREIGN,
  UNKNOWN, CONTESTED) from a table per topic, GID -> verdict, built from
  `get_publishers_info_by_topic` and rebuilt when a GID it does not hold arrives (a new
  publisher: at most every REFRESH_S per topic) or when the number of publishers changed
  (`look`, from the node's timer). The per-message cost is one dict look-up;
- CONTESTED: two or more publishers on the topic whose node has the owner's name and
  namespace (a second process started with the same node name), both alive: the receiver
  refuses both, and names them once per set (`on_contested`). A claimant is alive while it
  speaks: heard since the other claimant appeared in the graph, or within LIVE_S. A killed
  node's endpoints stay in the graph until its lease runs out (Fast DDS: 20 s), so the
  node started again in its place (ros2 launch's respawn, run_scenario --respawn) would
  otherwise share its name with a ghost; the dead one is silent since before its successor
  appeared, and a process takes far longer than LIVE_S to start again.

A message delivered inside this process (mill_common.intra_process) has no GID: it comes
from the topic's publisher in this process, which the bus names (LOCAL).
"""

from __future__ import annotations

import ctypes
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.type_support import check_is_valid_msg_type
from rclpy.waitable import NumberOfEntities, Waitable

from mill_common.checks import ANYONE, CONTESTED, FOREIGN, OWNER, UNKNOWN, Sender

LOCAL = b''  # the GID of a message delivered inside this process (no DDS endpoint)
REFRESH_S = 0.05  # the least time between two looks at one topic's publishers for a new GID
LIVE_S = 0.2  # a claimant heard this recently is alive, whenever it appeared
UNKNOWN_NODE = '_NODE_NAME_UNKNOWN_'  # an endpoint whose node discovery has not named yet


def gid_text(gid: bytes) -> str:
    """A GID as `ros2 topic info -v` prints it."""
    return '.'.join(f'{b:02x}' for b in gid)


def qualified(namespace: str, name: str) -> str:
    return f'{namespace.rstrip("/")}/{name}'


@dataclass
class _Topic:
    name: str  # as the node named it (relative to its namespace)
    owner: str
    verdicts: dict[bytes, Sender] = field(default_factory=dict)
    count: int = -1  # publishers at the last look
    looked: float = -1e9  # monotonic time of the last look
    claimants: dict[bytes, str] = field(default_factory=dict)  # GID -> name, of the owner's name
    appeared: dict[bytes, float] = field(default_factory=dict)  # claimant GID -> first seen
    heard: dict[bytes, float] = field(default_factory=dict)  # claimant GID -> last message
    reported: tuple[str, ...] = ()  # the claimants named last


class GraphOwners:
    def __init__(
        self,
        node: Node,
        local_publishers: Callable[[str], list[str]] | None = None,
        on_contested: Callable[[str, str, tuple[str, ...]], None] | None = None,
    ) -> None:
        """local_publishers: the nodes of this process publishing a (resolved) topic
        (mill_common.intra_process); on_contested(topic as watched, owner, claimants): told
        once per set of live claimants."""
        self._node = node
        self._namespace = node.get_namespace()
        self._local = local_publishers or (lambda topic: [])
        self._on_contested = on_contested
        self._topics: dict[str, _Topic] = {}

    def watch(self, topic: str, owner: str) -> str:
        """Identify the senders of `topic` against `owner` (a node name in this node's
        namespace); returns the resolved topic name the verdicts are asked with."""
        resolved = self._node.resolve_topic_name(topic)
        self._topics[resolved] = _Topic(topic, owner)
        return resolved

    def verdict(self, topic: str, gid: bytes) -> Sender:
        """Who sent a message of `topic` (resolved, watched) that arrived with `gid`."""
        t = self._topics.get(topic)
        if t is None or not t.owner:
            return ANYONE
        if gid == LOCAL:
            return self._local_verdict(topic, t)
        got = t.verdicts.get(gid)
        if got is None:
            if time.monotonic() - t.looked >= REFRESH_S:
                self._refresh(topic, t)
                got = t.verdicts.get(gid)
            if got is None:
                # While the graph shows the owner, a publisher it does not name yet is not
                # taken on its frame_id: it may be a second copy whose first commands would
                # otherwise drive the axis until discovery names it (issue 37 item 2).
                known = tuple(sorted(t.claimants.values()))
                return Sender(UNKNOWN, f'an unknown publisher (gid {gid_text(gid)})', known)
        if got.verdict != OWNER:
            return got
        now = time.monotonic()
        t.heard[gid] = now
        if len(t.claimants) < 2:
            return got
        return self._contest(t, gid, got, now)

    def look(self) -> None:
        """From a timer: look again at each topic whose number of publishers changed
        (counting costs a tenth of listing)."""
        for topic, t in self._topics.items():
            if t.owner and self._node.count_publishers(topic) != t.count:
                self._refresh(topic, t)

    def _contest(self, t: _Topic, gid: bytes, mine: Sender, now: float) -> Sender:
        """The verdict on a claimant's message while others claim the owner's name too: it
        is contested if another claimant is alive (heard since this one appeared, or
        within LIVE_S)."""
        since = min(t.appeared.get(gid, now), now - LIVE_S)
        alive = [g for g in t.claimants if g != gid and t.heard.get(g, -1e9) >= since]
        if not alive:
            return mine
        names = tuple(sorted(t.claimants[g] for g in (gid, *alive)))
        if names != t.reported:
            t.reported = names
            if self._on_contested is not None:
                self._on_contested(t.name, t.owner, names)
        return Sender(CONTESTED, mine.name, names)

    def _local_verdict(self, topic: str, t: _Topic) -> Sender:
        """A message from this process's publisher: the owner if it is the owner's node. No
        other process can contest it: while a node of this process publishes the topic, its
        readers here take nothing from DDS (mill_common.intra_process), and that module
        names the other publishers."""
        own = qualified(self._namespace, t.owner)
        local = self._local(topic)
        if own not in local:
            return Sender(FOREIGN, ', '.join(local) or 'a publisher in this process')
        return Sender(OWNER, own)

    def _refresh(self, topic: str, t: _Topic) -> None:
        t.looked = now = time.monotonic()
        infos = self._node.get_publishers_info_by_topic(topic)
        t.count = len(infos)
        own = qualified(self._namespace, t.owner)
        claimants: dict[bytes, str] = {}
        verdicts: dict[bytes, Sender] = {}
        for info in infos:
            gid = bytes(info.endpoint_gid)
            if info.node_name == UNKNOWN_NODE:
                t.count = -1  # discovery has not named it yet: look again next time
                continue
            who = qualified(info.node_namespace, info.node_name)
            if who == own:
                claimants[gid] = f'{who} (gid {gid_text(gid)})'
                verdicts[gid] = Sender(OWNER, who)
            else:
                verdicts[gid] = Sender(FOREIGN, who)
        t.appeared = {g: t.appeared.get(g, now) for g in claimants}
        t.heard = {g: h for g, h in t.heard.items() if g in claimants}
        t.claimants, t.verdicts = claimants, verdicts


# -- the take: serialized bytes and the publisher GID of each message ----------------------
class _Allocator(ctypes.Structure):
    _fields_ = [
        ('allocate', ctypes.c_void_p),
        ('deallocate', ctypes.c_void_p),
        ('reallocate', ctypes.c_void_p),
        ('zero_allocate', ctypes.c_void_p),
        ('state', ctypes.c_void_p),
    ]


class _Bytes(ctypes.Structure):  # rcl_serialized_message_t (rcutils_uint8_array_t)
    _fields_ = [
        ('buffer', ctypes.POINTER(ctypes.c_uint8)),
        ('buffer_length', ctypes.c_size_t),
        ('buffer_capacity', ctypes.c_size_t),
        ('allocator', _Allocator),
    ]


GID_SIZE = 16  # RMW_GID_STORAGE_SIZE of Jazzy's rmw


class _Gid(ctypes.Structure):
    _fields_ = [('implementation_identifier', ctypes.c_char_p), ('data', ctypes.c_uint8 * GID_SIZE)]


class _MessageInfo(ctypes.Structure):  # rmw_message_info_t
    _fields_ = [
        ('source_timestamp', ctypes.c_int64),
        ('received_timestamp', ctypes.c_int64),
        ('publication_sequence_number', ctypes.c_uint64),
        ('reception_sequence_number', ctypes.c_uint64),
        ('publisher_gid', _Gid),
        ('from_intra_process', ctypes.c_bool),
    ]


def _library(name: str) -> ctypes.CDLL:
    """A ROS library rclpy has loaded already (else the one beside the interpreter's)."""
    try:
        return ctypes.CDLL(name)
    except OSError:
        return ctypes.CDLL(os.path.join(sys.prefix, 'lib', name))


_RCL: Any = None
_RCUTILS: Any = None


def _libraries() -> tuple[Any, Any]:
    global _RCL, _RCUTILS
    if _RCL is None:
        rcl, rcutils = _library('librcl.so'), _library('librcutils.so')
        rcutils.rcutils_get_default_allocator.restype = _Allocator
        rcutils.rcutils_uint8_array_init.argtypes = [
            ctypes.POINTER(_Bytes),
            ctypes.c_size_t,
            ctypes.POINTER(_Allocator),
        ]
        rcutils.rcutils_uint8_array_fini.argtypes = [ctypes.POINTER(_Bytes)]
        rcl.rcl_take_serialized_message.argtypes = [
            ctypes.c_void_p,
            ctypes.POINTER(_Bytes),
            ctypes.POINTER(_MessageInfo),
            ctypes.c_void_p,
        ]
        rcl.rcl_take_serialized_message.restype = ctypes.c_int
        _RCL, _RCUTILS = rcl, rcutils
    return _RCL, _RCUTILS


class _Done:
    """What GidSubscription.execute returns once the callback has run: called (a Task of
    rclpy's EventsExecutor) or awaited (rclpy's Python executors), it does nothing."""

    def __call__(self) -> None:
        return None

    def __await__(self) -> Iterator[None]:
        return iter(())


DONE = _Done()


class GidSubscription(Waitable):
    """A raw subscription whose callback gets (bytes, publisher GID) of each message.

    Made and destroyed like a node's subscription (`destroy`); in the graph it is the
    node's subscription of the topic, with the given QoS.
    """

    def __init__(
        self,
        node: Node,
        msg_type: Any,
        topic: str,
        callback: Callable[[bytes, bytes], None],
        qos: QoSProfile | int,
    ) -> None:
        super().__init__(node.default_callback_group)
        check_is_valid_msg_type(msg_type)
        profile = qos if isinstance(qos, QoSProfile) else QoSProfile(depth=qos)
        with node.handle:
            self.handle = _rclpy.Subscription(
                node.handle, msg_type, topic, profile.get_c_qos_profile()
            )
        self.callback = callback
        self._rcl, rcutils = _libraries()
        self._bytes = _Bytes()
        allocator = rcutils.rcutils_get_default_allocator()
        if rcutils.rcutils_uint8_array_init(ctypes.byref(self._bytes), 4096, allocator):
            raise MemoryError(f'no buffer for the messages of {topic}')
        self._info = _MessageInfo()
        self._bytes_ref, self._info_ref = ctypes.byref(self._bytes), ctypes.byref(self._info)
        self._pointer = self.handle.pointer
        self._index = 0
        self._node = node
        node.add_waitable(self)

    def get_publisher_count(self) -> int:
        with self.handle:
            return int(self.handle.get_publisher_count())

    def destroy(self) -> None:
        self._node.remove_waitable(self)
        self.handle.destroy_when_not_in_use()
        if _RCUTILS is not None:
            _RCUTILS.rcutils_uint8_array_fini(ctypes.byref(self._bytes))

    # -- Waitable ------------------------------------------------------------------------------
    def __enter__(self) -> None:
        self.handle.__enter__()

    def __exit__(self, *exc: Any) -> None:
        self.handle.__exit__(*exc)

    def get_num_entities(self) -> NumberOfEntities:
        return NumberOfEntities(1, 0, 0, 0, 0, 0)

    def add_to_wait_set(self, wait_set: Any) -> None:
        self._index = wait_set.add_subscription(self.handle)

    def is_ready(self, wait_set: Any) -> bool:
        return bool(wait_set.is_ready('subscription', self._index))

    def take_data(self) -> tuple[bytes, bytes] | None:
        with self.handle:
            if self._rcl.rcl_take_serialized_message(
                self._pointer, self._bytes_ref, self._info_ref, None
            ):
                return None  # nothing there after all (RCL_RET_SUBSCRIPTION_TAKE_FAILED)
            data = self._bytes
            gid = bytes(self._info.publisher_gid.data)
            return ctypes.string_at(data.buffer, data.buffer_length), gid

    def execute(self, taken: tuple[bytes, bytes] | None) -> _Done:  # type: ignore[override]
        """Run the callback now, not in a coroutine: rclpy's EventsExecutor makes a Task of
        what `execute` returns (the callback in a coroutine cost 8-10 µs more per message,
        a third of the take: docs/performance.md, "What limits it"); what it gets here is
        done already, and the SingleThreadedExecutor can await it."""
        if taken is not None:
            self.callback(*taken)
        return DONE
