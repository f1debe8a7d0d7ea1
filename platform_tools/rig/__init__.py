"""The rig description: one validated file that says what the rig is (see config/rig.yaml)."""
from .loader import DEFAULT_RIG, RigError, load_rig
from .model import Rig, SensorFrame, frames_table

__all__ = ["DEFAULT_RIG", "RigError", "load_rig", "Rig", "SensorFrame", "frames_table"]
