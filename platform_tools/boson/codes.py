"""FLR_RESULT codes and the package's error types.

Every FLR_RESULT code has its own exception class (``CamBusy``, ``NotReady``, ``RangeError`` ...),
all subclasses of :class:`CameraError`; :func:`error_for` turns a reply status into one. Codes the
table does not know become :class:`UnknownResult`. Transport problems (no reply, garbage, the port
gone) are :class:`TransportError` subclasses. Code values: FLIR Boson SDK 3.0 ReturnCodes.h.
"""
from __future__ import annotations

OK = 0x000

#: code -> (class name, what it means)
RESULTS: dict[int, tuple[str, str]] = {
    0x001: ("UartUnspecifiedFailure", "UART unspecified failure"),
    0x002: ("UartPortFailure", "UART port failure"),
    0x003: ("UartReceiveTimeout", "UART receive timeout"),
    0x004: ("UartPortAlreadyOpen", "UART port already open"),
    0x110: ("SdkApiUnspecifiedFailure", "SDK API unspecified failure"),
    0x111: ("SdkApiNotDefined", "SDK API not defined"),
    0x120: ("SdkPackagerFailure", "SDK packager unspecified failure"),
    0x12F: ("SdkPackagerOverflow", "SDK packager buffer overflow"),
    0x130: ("SdkDispatcherFailure", "SDK dispatcher unspecified failure"),
    0x131: ("SequenceMismatch", "reply sequence number does not match the request"),
    0x132: ("IdMismatch", "reply function id does not match the request"),
    0x133: ("MalformedStatus", "malformed status"),
    0x140: ("SdkTransmitFailure", "SDK transmit failure"),
    0x150: ("CamReceiveFailure", "camera receive failure"),
    0x160: ("CamDispatcherFailure", "camera dispatcher unspecified failure"),
    0x161: ("BadCommandId", "the camera does not know this function id"),
    0x162: ("BadPayloadStatus", "bad payload status"),
    0x170: ("CamPackagerFailure", "camera packager unspecified failure"),
    0x17D: ("InsufficientBytes", "payload too short for this command"),
    0x17E: ("ExcessBytes", "payload too long for this command"),
    0x17F: ("CamPackagerOverflow", "camera packager buffer overflow"),
    0x180: ("CamApiFailure", "camera API unspecified failure"),
    0x181: ("InvalidInput", "invalid input"),
    0x190: ("CamTransmitFailure", "camera transmit failure"),
    0x1A0: ("ApiReceiveFailure", "API receive failure"),
    0x1B0: ("FeatureNotEnabled", "feature not enabled on this camera"),
    0x201: ("FlrError", "error"),
    0x202: ("NotReady", "camera not ready"),
    0x203: ("RangeError", "value out of range"),
    0x204: ("ChecksumError", "checksum error"),
    0x205: ("BadArgPointer", "bad argument pointer"),
    0x206: ("DataSizeError", "data size error"),
    0x207: ("UndefinedFunction", "undefined function"),
    0x208: ("IllegalAddress", "illegal address"),
    0x209: ("BadOutType", "bad output type"),
    0x20A: ("BadOutInterface", "bad output interface"),
    0x20B: ("DeprecatedFunction", "deprecated function"),
    0x265: ("CommPortNotOpen", "comm port not open"),
    0x266: ("CommInvalidPort", "invalid comm port"),
    0x267: ("CommRangeError", "comm range error"),
    0x268: ("CommCreateError", "error creating comm"),
    0x269: ("CommStartError", "error starting comm"),
    0x26A: ("CommCloseError", "error closing comm"),
    0x26B: ("CommChecksumError", "comm checksum error"),
    0x26C: ("CommNoDevice", "no comm device"),
    0x26D: ("CommTimeout", "comm timeout or write error"),
    0x26E: ("CommReadError", "comm read error"),
    0x26F: ("CommCountError", "comm count error"),
    0x27E: ("OperationCanceled", "operation cancelled"),
    0x27F: ("UndefinedErrorCode", "undefined error code"),
    0x280: ("NotSubblockBoundary", "length not on a sub-block boundary"),
    0x281: ("ConfigError", "configuration error"),
    0x282: ("I2cError", "I2C error"),
    0x283: ("CamBusy", "camera busy"),
    0x284: ("HeaterError", "heater error"),
    0x285: ("WindowError", "window error"),
    0x286: ("VbattError", "battery voltage error"),
    0x300: ("SymbologyFailure", "symbology unspecified failure"),
    0x301: ("SymbologyInvalidPosition", "symbology invalid position"),
    0x320: ("ResourceNotAvailable", "resource not available"),
    0x321: ("ResourceNotImplemented", "resource not implemented"),
    0x322: ("ResourceRangeError", "resource range error"),
    0x384: ("SystemInitError", "system init error"),
    0x3E8: ("SdioError", "SDIO error"),
    0x44C: ("StorageSdError", "SD storage error"),
    0x4B0: ("UsbVideoError", "USB video error"),
    0x514: ("UsbCdcError", "USB CDC error"),
    0x578: ("UsbMsdError", "USB mass storage error"),
    0x5DC: ("NetError", "network error"),
    0x640: ("BluetoothError", "bluetooth error"),
    0x6A4: ("FlashError", "flash error"),
    0x708: ("FlashHeaderErased", "flash header erased"),
    0x709: ("FlashHeaderPartialWrite", "flash header partially written"),
    0x70A: ("FlashHeaderWrongFooterId", "flash header: wrong footer id"),
    0x70B: ("FlashHeaderWrongFooterMetadata", "flash header: wrong footer metadata"),
    0x70C: ("FlashHeaderWrongFooterType", "flash header: wrong footer type"),
    0x70D: ("FlashHeaderWrongHeaderSize", "flash header: wrong header size"),
    0x70E: ("FlashHeaderFooterCrcError", "flash header: footer CRC error"),
}

#: codes worth retrying after a short back-off: the camera is alive but not ready for this yet
TRANSIENT = frozenset({0x202, 0x283})


class BosonError(Exception):
    """Anything that went wrong talking to a Boson. ``str()`` is one line for the user."""


class CameraError(BosonError):
    """The camera answered with a non-zero FLR_RESULT status."""
    code: int = -1
    meaning: str = "unknown result code"
    transient: bool = False

    def __init__(self, code: int | None = None, command: str = "", camera: str = ""):
        if code is not None:
            self.code = code
        self.command = command
        self.camera = camera
        super().__init__(self._text())

    @property
    def result_name(self) -> str:
        return type(self).__name__

    def _text(self) -> str:
        where = f"{self.camera}: " if self.camera else ""
        what = f" to {self.command}" if self.command else ""
        return f"{where}camera replied {self.result_name} (0x{self.code:03X}, {self.meaning}){what}"


class UnknownResult(CameraError):
    meaning = "a result code this tool does not know"


#: code -> exception class, one per FLR_RESULT code
ERRORS: dict[int, type[CameraError]] = {}
for _code, (_name, _meaning) in RESULTS.items():
    _cls = type(_name, (CameraError,), {"code": _code, "meaning": _meaning, "transient": _code in TRANSIENT,
                                        "__doc__": f"FLR_RESULT 0x{_code:03X}: {_meaning}."})
    globals()[_name] = _cls
    ERRORS[_code] = _cls
del _code, _name, _meaning, _cls


def error_for(code: int, command: str = "", camera: str = "") -> CameraError:
    """The named exception for a non-zero reply status."""
    if code == OK:
        raise ValueError("status 0 is success, not an error")
    cls = ERRORS.get(code)
    return cls(command=command, camera=camera) if cls else UnknownResult(code, command=command, camera=camera)


class TransportError(BosonError):
    """The bytes did not get there or back."""


class PortNotFound(TransportError):
    pass


class PortPermission(TransportError):
    pass


class PortBusy(TransportError):
    pass


#: a port that cannot be opened is bad input (exit 2), not a failed check: the user names or fixes it
PORT_PROBLEMS = (PortNotFound, PortPermission, PortBusy)


class PortGone(TransportError):
    """The port vanished (camera rebooted or unplugged) and did not come back in time."""


class ReplyTimeout(TransportError):
    """No matching reply in time."""


class BadReply(TransportError):
    """Bytes came back but not a valid reply (bad CRC, bad framing, wrong payload size)."""


class IdentityMismatch(BosonError):
    """The camera on a port is not the camera the rig description names."""
