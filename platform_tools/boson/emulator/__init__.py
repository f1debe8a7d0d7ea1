"""An emulated FLIR Boson: a stateful camera model (``state``), a simulated capture-card trigger
(``trigger``), fault injection (``faults``) and the device that serves it all on a pseudo-terminal
with a by-id link (``device``)."""
from .device import EmulatedBoson
from .faults import FaultRule, parse_faults
from .state import BosonState
from .trigger import Trigger

__all__ = ["EmulatedBoson", "FaultRule", "parse_faults", "BosonState", "Trigger"]
