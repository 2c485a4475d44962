"""Plant node: the drive front end (mill_plant.drive_node) over the simulated machine.

The simulated three-axis machine (Beltrán 2013 eq. 1-4 and the other papers' axis models,
mill_plant.simulated_machine) behind the same front end a hardware driver uses: lockstep
(the default: the plant is the clock of the simulation and waits for the commands of each
step, so results do not depend on DDS latency or machine load) or realtime (the machine
advances on the wall clock and holds the newest command, as a drive does).
"""

from __future__ import annotations

from typing import Any

from mill_common.node_main import run_node

from mill_plant.config import parameter_specs
from mill_plant.drive_node import DriveNode
from mill_plant.simulated_machine import SimulatedMachine


def make_node(**options: Any) -> DriveNode:
    """The plant node; `options` go to rclpy's Node (a container passes `cli_args`)."""
    return DriveNode(SimulatedMachine, parameter_specs(), **options)


def main(argv: list[str] | None = None) -> int:
    return run_node(
        make_node,
        'plant_node',
        'Simulated three-axis milling machine behind the drive front end: lockstep (the '
        'clock of the simulation) or realtime (wall clock, zero-order hold).',
        parameter_specs(),
        argv,
    )


if __name__ == '__main__':
    raise SystemExit(main())
