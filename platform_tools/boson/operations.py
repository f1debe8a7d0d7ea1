"""What the boson-* commands and the device's pre-flight do with cameras: open one, read its identity
and state, measure its frame rate, run or set its FFC, restore its factory settings, send a raw
command, and run any of these on every selected camera at once.

The functions taking a :class:`BosonClient` raise :class:`BosonError` for a camera problem;
:func:`on_camera` turns that into the ``error`` of the camera's row, so one camera's failure never
stops the others. Rows are plain dicts, ready for JSON.
"""
from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Sequence, TypeVar

from . import commands as C
from .client import BosonClient, Timeouts
from .codes import PORT_PROBLEMS, BosonError, CameraError
from .discovery import Target
from .transport import SerialTransport

T = TypeVar("T")


# ---------------------------------------------------------------------------- cameras
def open_client(target: Target, timeouts: Timeouts = Timeouts(), retries: int = 3) -> BosonClient:
    """An open client on the target's serial port (raises TransportError when it cannot be opened)."""
    return BosonClient(SerialTransport(target.port), timeouts=timeouts, retries=retries, label=target.label).open()


class ClientPool:
    """One open client per port for a whole command: identity asks each port its serial number
    (platform_tools.boson.identity), and the work after it goes through the same client, so the serial
    is read once (``BosonClient.camera_serial``) and a slow camera's latency, learned from its first
    reply, is kept instead of being learned again (a timeout) by a new client. Closes every client on
    exit."""

    def __init__(self, timeouts: Timeouts = Timeouts(), retries: int = 3, *,
                 opener: Callable[[Target, Timeouts, int], BosonClient] | None = None):
        self.timeouts, self.retries = timeouts, retries
        self._opener = opener or open_client      # how a port is opened (a test passes a loopback one)
        self._clients: dict[str, BosonClient] = {}
        self._lock = threading.Lock()

    def open(self, target: Target) -> BosonClient:
        """The open client on ``target.port`` (opened now if needed; TransportError when it cannot be),
        labelled as the target."""
        with self._lock:
            client = self._clients.get(target.port)
        if client is None or not client.transport.is_open:
            client = self._opener(target, self.timeouts, self.retries)
            with self._lock:
                self._clients[target.port] = client
        client.label = target.label
        return client

    def keep(self, ports) -> None:
        """Close the clients of every other port (cameras the command will not touch: their ports are
        opened exclusively, so another program may want them)."""
        wanted = set(ports)
        with self._lock:
            drop = [p for p in self._clients if p not in wanted]
            clients = [self._clients.pop(p) for p in drop]
        for client in clients:
            client.close()

    def close(self) -> None:
        self.keep(())

    def __enter__(self) -> "ClientPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def per_camera(targets: Sequence[Target], work: Callable[[Target], T]) -> list[T]:
    """``work(target)`` on every camera at once, results in the order of ``targets``."""
    with ThreadPoolExecutor(max_workers=max(1, len(targets))) as pool:
        return list(pool.map(work, targets))


def on_camera(target: Target, pool: ClientPool, work: Callable[[BosonClient], dict], **row: Any) -> dict:
    """``row.update(work(client))`` with the pool's client on the target (the pool closes it); a
    BosonError becomes ``row["error"]``. The row starts with the target's label and port (and the keyword
    arguments); a port that cannot be opened (missing, denied, in use) also sets ``row["port_problem"]``
    (bad input: exit 2)."""
    out: dict = {"label": target.label, "port": target.port, **row}
    try:
        client = pool.open(target)
    except PORT_PROBLEMS as exc:
        out["error"], out["port_problem"] = str(exc), True
        return out
    except BosonError as exc:
        out["error"] = str(exc)
        return out
    try:
        out.update(work(client))
    except BosonError as exc:
        out["error"] = str(exc)
    return out


def error_line(row: dict) -> str:
    """A row's error as one line that starts with the camera's label."""
    return row["error"] if row["error"].startswith(row["label"]) else f"{row['label']}: {row['error']}"


# ---------------------------------------------------------------------------- identity and state
def _firmware(rev: Any) -> str:
    return ".".join(str(v) for v in rev) if isinstance(rev, (tuple, list)) else str(rev)


#: what `read_info` can read: key -> (command, how its reply is shown); enums are shown by name
INFO: dict[str, tuple[C.Command, Callable[[Any], Any]]] = {
    "serial": (C.GET_CAMERA_SN, C.enum_name),
    "sensor_serial": (C.GET_SENSOR_SN, C.enum_name),
    "part_number": (C.GET_CAMERA_PN, C.enum_name),
    "firmware": (C.GET_SOFTWARE_REV, _firmware),                 # "major.minor.patch"
    "fpa_temp_c": (C.GET_FPA_TEMP_C, lambda v: v / 10.0),        # the reply is in 0.1 degC
    "sync_mode": (C.GET_EXT_SYNC, C.enum_name),
    "ffc_mode": (C.GET_FFC_MODE, C.enum_name),
    "ffc_status": (C.GET_FFC_STATUS, C.enum_name),
    "gain_mode": (C.GET_GAIN_MODE, C.enum_name),
    "telemetry": (C.GET_TELEMETRY, C.enum_name),
    "telemetry_location": (C.GET_TELEMETRY_LOCATION, C.enum_name),
    "telemetry_packing": (C.GET_TELEMETRY_PACKING, C.enum_name),
    "frame_count": (C.GET_FRAME_COUNT, C.enum_name),
}
#: what `platform_tools boson-info` shows
INFO_KEYS = ("serial", "sensor_serial", "part_number", "firmware", "fpa_temp_c", "sync_mode", "ffc_mode",
             "ffc_status", "gain_mode", "frame_count")


def read_info(client: BosonClient, keys: Sequence[str] = INFO_KEYS) -> dict[str, Any]:
    """The camera's values for ``keys`` (of :data:`INFO`), read in that order."""
    out = {}
    for key in keys:
        command, show = INFO[key]
        value = client.camera_serial() if command is C.GET_CAMERA_SN else client.call(command)
        out[key] = show(value)
    return out


def camera_info(client: BosonClient, expected_serial: int | None, keys: Sequence[str] = INFO_KEYS) -> dict:
    """:func:`read_info`, with an ``error`` when the camera answers with another serial number."""
    row = read_info(client, keys)
    if expected_serial is not None and row["serial"] != expected_serial:
        row["error"] = f"answers as SN {row['serial']}, not SN {expected_serial}"
    return row


def measure_frame_rate(client: BosonClient, window_s: float) -> float:
    """Frames per second over ``window_s`` seconds, from the ISP frame counter (32 bits, wraps)."""
    c0, t0 = client.call(C.GET_FRAME_COUNT), time.monotonic()
    time.sleep(window_s)
    c1, t1 = client.call(C.GET_FRAME_COUNT), time.monotonic()
    return ((c1 - c0) & 0xFFFFFFFF) / (t1 - t0)


# ---------------------------------------------------------------------------- actions
FFC_BUSY = (C.FfcStatus.IMMINENT, C.FfcStatus.IN_PROGRESS)


def run_ffc(client: BosonClient, wait_s: float | None = None, poll_s: float = 0.05) -> dict:
    """Trigger a flat-field correction and poll its status every ``poll_s`` until it is done or
    ``wait_s`` passed (default: the client's slow-command timeout + 2 s)."""
    client.call(C.RUN_FFC)
    deadline = time.monotonic() + (client.timeouts.slow_s + 2.0 if wait_s is None else wait_s)
    status = client.call(C.GET_FFC_STATUS)
    while status in FFC_BUSY and time.monotonic() < deadline:
        time.sleep(poll_s)
        status = client.call(C.GET_FFC_STATUS)
    row = {"ffc_status": C.enum_name(status)}
    if status in FFC_BUSY:
        row["error"] = "FFC did not complete in time"
    return row


def set_ffc_mode(client: BosonClient, mode: str) -> dict:
    """``mode`` "auto" or "manual": written only when it differs, then read back."""
    row = {"before": C.enum_name(client.call(C.GET_FFC_MODE))}
    if row["before"] != mode:
        client.call(C.SET_FFC_MODE, C.FfcMode[mode.upper()])
    row["ffc_mode"] = C.enum_name(client.call(C.GET_FFC_MODE))
    if row["ffc_mode"] != mode:
        row["error"] = f"FFC mode reads back {row['ffc_mode']}"
    return row


def restore_defaults(client: BosonClient, persist: bool) -> dict:
    """Factory settings now (and, with ``persist``, as power-on defaults); what they read back."""
    client.call(C.RESTORE_DEFAULTS)
    if persist:
        client.call(C.WRITE_FLASH)
    return {"sync_mode": C.enum_name(client.call(C.GET_EXT_SYNC)),
            "ffc_mode": C.enum_name(client.call(C.GET_FFC_MODE)), "persisted": persist}


def raw_request(function_id: int, payload: bytes) -> dict:
    """How a raw request is shown: its function id, the command it is (None if unknown), its payload."""
    cmd = C.BY_ID.get(function_id)
    return {"function_id": f"0x{function_id:08X}", "command": cmd.name if cmd else None, "request": payload.hex()}


def raw_call(client: BosonClient, function_id: int, payload: bytes) -> dict:
    """Send any function id with a payload; the reply in hex, decoded when the command is known.
    A camera's error code is reported in the row (``status``, ``result``, ``error``), not raised."""
    cmd = C.BY_ID.get(function_id)
    try:
        reply = client.call_raw(function_id, payload, command=cmd)
    except CameraError as exc:
        return {"status": f"0x{exc.code:03X}", "result": exc.result_name, "error": str(exc)}
    row = {"status": "0x000", "reply": reply.hex()}
    if cmd is not None and cmd.reply:
        try:
            row["value"] = C.enum_name(cmd.decode_reply(reply))
        except BosonError:
            pass
    return row
