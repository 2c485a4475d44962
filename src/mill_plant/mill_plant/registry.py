"""Name → class for the plant's pieces: axis models and cutting-force models (ROS-free).

The plant node's `axis_model` (one name per axis) and `cutting_model` parameters choose
among these; each class's parameters are `<PREFIX>.<name>` on the node (the rigid model's
keep their plain names, see mill_plant.config).
"""

from __future__ import annotations

from mill_common.registry import Registry

from mill_plant.cutting import CuttingForceModel, NoCutting, StepForce
from mill_plant.harmonic_force import HarmonicForce
from mill_plant.kline_force import KlineCuttingForce
from mill_plant.load_force import LoadForce
from mill_plant.models.base import AxisModel
from mill_plant.models.flexible import FlexibleAxisModel
from mill_plant.models.rigid import RigidAxisModel
from mill_plant.models.transfer_function import TransferFunctionAxisModel
from mill_plant.models.velocity_drive import VelocityDriveAxisModel

AXIS_MODELS: Registry[AxisModel] = Registry(
    'axis_model',
    {
        'rigid': RigidAxisModel,  # Beltrán 2013 eq. (1)-(3); Chávez-Conde eq. (1)-(3), gravity
        'flexible': FlexibleAxisModel,  # Chávez-Conde eq. (4)-(6)
        'transfer_function': TransferFunctionAxisModel,  # Maharof 2018 eq. (1), input in V
        'velocity_drive': VelocityDriveAxisModel,  # Hatwesh 2013 eq. (1)-(6), input in V
    },
)

CUTTING_MODELS: Registry[CuttingForceModel] = Registry(
    'cutting_model',
    {
        'kline': KlineCuttingForce,  # Beltrán 2013 eq. (4)
        'step': StepForce,  # a constant force from a start time on
        'harmonic': HarmonicForce,  # Maharof 2018 §3, eq. (5)
        'load': LoadForce,  # a machine's process load: constant + harmonic, while moving
        'none': NoCutting,  # air cutting
    },
)
