"""The clock node's start-up and liveness decisions, on a fake clock."""

from __future__ import annotations

from mill_common.lockstep import Action, LockstepWatchdog


def watchdog(startup: float = 10.0, lockstep: float = 5.0) -> LockstepWatchdog:
    return LockstepWatchdog(0.0, lambda: startup, lambda: lockstep)


def test_starts_after_peers_have_been_present_for_the_settle_time() -> None:
    w = watchdog()
    peers: list[str] = ['no publisher on /mill/x/joint_command']
    assert w.tick(1.0, lambda: peers) is Action.WAIT
    peers.clear()
    assert w.tick(1.1, lambda: peers) is Action.WAIT  # present, settling
    peers.append('gone again')
    assert w.tick(1.3, lambda: peers) is Action.WAIT  # settling restarts
    peers.clear()
    assert w.tick(1.4, lambda: peers) is Action.WAIT
    assert w.tick(1.8, lambda: peers) is Action.WAIT  # 0.4 s < 0.5 s
    assert w.tick(1.95, lambda: peers) is Action.START
    assert w.started


def test_an_unanswered_step_is_offered_again_each_second() -> None:
    w = watchdog()
    w.tick(0.0, list)
    assert w.tick(0.5, list) is Action.START
    assert w.tick(1.4, list) is Action.WAIT
    assert w.tick(1.6, list) is Action.OFFER_AGAIN
    assert w.tick(2.0, list) is Action.WAIT
    assert w.tick(2.7, list) is Action.OFFER_AGAIN
    w.progressed(2.8)
    assert w.tick(3.7, list) is Action.WAIT  # answered: the next step has a second
    assert w.waited(3.7) == 3.7 - 2.8
    assert w.tick(3.9, list) is Action.OFFER_AGAIN  # any step, not only step 0
    w.progressed(4.0)
    assert w.tick(4.5, list) is Action.WAIT


def test_timeouts_before_and_after_the_start() -> None:
    w = watchdog(startup=10.0)
    assert w.tick(9.9, lambda: ['x']) is Action.WAIT
    assert w.tick(10.1, lambda: ['x']) is Action.PEERS_MISSING
    w = watchdog(lockstep=5.0)
    w.tick(0.0, list)
    w.tick(0.5, list)  # START
    w.progressed(3.0)
    assert w.tick(7.9, list) is not Action.STALLED
    assert w.tick(8.1, list) is Action.STALLED
