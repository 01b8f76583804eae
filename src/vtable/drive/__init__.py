"""Drive compensation: the drive that makes the specimen feel the target (report §10.2)."""

from vtable.drive.compensate import CAP, OBJECTIVES, REGULARISATION, compensate
from vtable.drive.plant import DrivePlant
from vtable.drive.result import DriveResult
from vtable.drive.target import DRIVE_FS, Target, read_target

__all__ = ["CAP", "DRIVE_FS", "OBJECTIVES", "REGULARISATION", "DrivePlant", "DriveResult",
           "Target", "compensate", "read_target"]
