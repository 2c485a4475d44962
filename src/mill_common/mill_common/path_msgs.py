"""nav_msgs/Path messages of x, y, z points (mill_common.tool_path) in the machine's frame.

Both path topics are drawn in `machine_urdf.BASE_LINK`, the frame in which the tool's point
is (x, y, z), prefixed in a namespace (`machine_a/mill_base`, machine_urdf.frame); every
pose's orientation is the identity.
"""

from __future__ import annotations

from collections.abc import Sequence

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path

from mill_common.machine_urdf import BASE_LINK, frame
from mill_common.ros import to_stamp
from mill_common.tool_path import Point


def path_message(
    stamp_ns: int, points: Sequence[Point], stamps_ns: Sequence[int] = (), ns: str = '/'
) -> Path:
    """A Path stamped `stamp_ns` through `points` in the base frame of the machine in
    namespace `ns`; each pose stamped with its own time (`stamps_ns`, one per point) or,
    without them, with the path's."""
    base = frame(BASE_LINK, ns)
    msg = Path()
    msg.header.stamp = to_stamp(stamp_ns)
    msg.header.frame_id = base
    poses = []
    for i, (x, y, z) in enumerate(points):
        pose = PoseStamped()
        pose.header.stamp = to_stamp(stamps_ns[i] if stamps_ns else stamp_ns)
        pose.header.frame_id = base
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = x, y, z
        pose.pose.orientation.w = 1.0
        poses.append(pose)
    msg.poses = poses
    return msg
