"""An emulated FLIR Boson: a stateful camera model (``state``), a simulated capture-card trigger
(``trigger``), fault injection (``faults``) and the device that serves it all on a pseudo-terminal
with a by-id link (``device``); ``answer_with(state)`` answers on bytes, for the in-memory loopback
transport; ``fleet`` runs several cameras at once, as `platform_tools boson-emulator` does."""
from .device import EmulatedBoson
from .faults import FaultRule, parse_faults
from .state import BosonState, answer_with
from .trigger import Trigger

__all__ = ["EmulatedBoson", "FaultRule", "parse_faults", "BosonState", "Trigger", "answer_with"]
