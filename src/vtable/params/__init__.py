"""Typed parameter objects (SI inside) with the report's presets."""

from vtable.params import presets
from vtable.params.base import Params, read_toml
from vtable.params.loops import (
    HorizontalSpring,
    HybridParams,
    MechanicalParams,
    OpenLoop,
    RockingSpring,
    StructureRatios,
    TableSDOFParams,
    TwoDirectionalParams,
)
from vtable.params.specimen import (
    NoSpecimen,
    RigidBlock,
    SDOFSpecimen,
    ShearBuilding,
    Specimen,
    specimen_from_dict,
)
from vtable.params.table import (
    ActuatorSpec,
    ControlSettings,
    DirectionSettings,
    EERCTable,
    KnobFactors,
    ServoConstants,
    TableGeometry,
    TableSpecs,
)

__all__ = [
    "ActuatorSpec", "ControlSettings", "DirectionSettings", "EERCTable", "HorizontalSpring",
    "HybridParams", "KnobFactors", "MechanicalParams", "NoSpecimen", "OpenLoop", "Params",
    "RigidBlock", "RockingSpring", "SDOFSpecimen", "ServoConstants", "ShearBuilding",
    "Specimen", "StructureRatios", "TableGeometry", "TableSDOFParams", "TableSpecs",
    "TwoDirectionalParams", "presets", "read_toml", "specimen_from_dict",
]
