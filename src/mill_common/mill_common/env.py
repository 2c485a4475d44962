"""Environment for ROS processes the project starts: loopback-only DDS, private domain.

Nothing here overrides a value the user has set.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

# Fast DDS repairs a lost reliable sample at the writer's next heartbeat, every 3 s by
# default: a lockstep graph waits that long for it. The project's profile announces every
# 100 ms (the file says so); a profile the user names wins.
FASTDDS_PROFILE = Path(__file__).with_name('fastdds_profile.xml')


def private_domain_id(seed: int | None = None) -> str:
    """A domain id in 1..100 derived from the process id, so parallel runs rarely meet."""
    return str(1 + (os.getpid() if seed is None else seed) % 100)


def ros_environment(base: Mapping[str, str] | None = None, domain_id: str | None = None) -> dict:
    """Copy of `base` (default os.environ) with DDS kept on loopback and a domain id set."""
    env = dict(os.environ if base is None else base)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env.setdefault('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    env.setdefault('FASTRTPS_DEFAULT_PROFILES_FILE', str(FASTDDS_PROFILE))
    if domain_id is not None:
        env['ROS_DOMAIN_ID'] = str(domain_id)
    elif 'ROS_DOMAIN_ID' not in env:
        env['ROS_DOMAIN_ID'] = private_domain_id()
    # Children print their logs as they happen, not in blocks at exit.
    env.setdefault('PYTHONUNBUFFERED', '1')
    env.setdefault('RCUTILS_LOGGING_BUFFERED_STREAM', '0')
    return env


def apply_to_current_process(domain_id: str | None = None) -> None:
    """Set the loopback defaults in os.environ before rclpy.init()."""
    os.environ.update(ros_environment(domain_id=domain_id))
