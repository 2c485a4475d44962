"""The runner as a lifecycle client: bring a drive that runs elsewhere (another host, a
container) to active where the runner would have started it, brake it at the end, and
release its latched axes when the operator asked to re-arm them (`release`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from mill_common.progress import Progress


def activate(
    node: Any,
    executor: Any,
    target: str,
    progress: Progress,
    started: Callable[[], bool],
    wait: float,
) -> None:
    """Bring a lifecycle node that runs elsewhere to active, where the runner would start it.

    A drive started with autostart false waits for this: it then starts after the graph, as
    a drive the runner starts itself does. One that runs by itself (`started`: its first
    step has arrived), or is active already, is left alone. Discovering the services of a
    node on another host or in a busy process can take long: wait for them up to `wait` s.
    """
    from lifecycle_msgs.msg import State, Transition
    from lifecycle_msgs.srv import ChangeState, GetState

    steps = {
        State.PRIMARY_STATE_UNCONFIGURED: ['configure', 'activate'],
        State.PRIMARY_STATE_INACTIVE: ['activate'],
    }
    ids = {
        'configure': Transition.TRANSITION_CONFIGURE,
        'activate': Transition.TRANSITION_ACTIVATE,
    }
    get = node.create_client(GetState, f'{target}/get_state')
    change = node.create_client(ChangeState, f'{target}/change_state')
    try:
        t0 = time.monotonic()
        said = False
        while not get.service_is_ready():  # spinning: the job may already be under way
            if started():
                progress.note(f'{target} has no lifecycle services: it started by itself')
                return
            if time.monotonic() - t0 > wait:
                progress.note(f'{target}: no lifecycle services and no step within {wait:g} s')
                return
            if not said and time.monotonic() - t0 > 5.0:
                progress.note(f'waiting for the lifecycle services of {target} (discovery)')
                said = True
            executor.spin_once(timeout_sec=0.05)
        state = _call(executor, get, GetState.Request())
        todo = steps.get(state.current_state.id, []) if state is not None else []
        for name in todo:
            request = ChangeState.Request()
            request.transition.id = ids[name]
            result = _call(executor, change, request)
            if result is None or not result.success:
                progress.note(f'{target}: {name} failed')
                return
        if todo:
            progress.note(f'{target}: activated')
    finally:
        node.destroy_client(get)
        node.destroy_client(change)


def _call(executor: Any, client: Any, request: Any, timeout: float = 30.0) -> Any:
    """The response of a service call, None if none came within timeout."""
    future = client.call_async(request)
    deadline = time.monotonic() + timeout
    while not future.done() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    return future.result() if future.done() else None


def deactivate(node: Any, executor: Any, target: str, progress: Progress) -> None:
    """Ask a lifecycle node (the drive) to deactivate: it brakes every axis."""
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState

    client = node.create_client(ChangeState, f'{target}/change_state')
    try:
        if not client.wait_for_service(timeout_sec=2.0):
            progress.note(f'{target} has no lifecycle: it brakes when the commands stop')
            return
        request = ChangeState.Request()
        request.transition.id = Transition.TRANSITION_DEACTIVATE
        result = _call(executor, client, request)
        ok = result is not None and result.success
        progress.note(
            f'{target}: deactivated (axes braked)' if ok else f'{target}: deactivate failed'
        )
    finally:
        node.destroy_client(client)


def release(node: Any, executor: Any, target: str, wait: float) -> str | None:
    """Call the drive's `~/release` (std_srvs/Trigger): its answer (what it released), or
    None when it offers no such service within `wait` s."""
    from std_srvs.srv import Trigger

    client = node.create_client(Trigger, f'{target}/release')
    try:
        deadline = time.monotonic() + wait
        while not client.service_is_ready():
            if time.monotonic() > deadline:
                return None
            executor.spin_once(timeout_sec=0.05)
        response = _call(executor, client, Trigger.Request())
        return None if response is None else str(response.message)
    finally:
        node.destroy_client(client)
