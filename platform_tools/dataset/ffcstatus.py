"""A thermal camera's FFC status messages to ``(host stamp ns, ffc_status)`` rows (2: FFC in progress, 0: not).

Two message types are read (the released TartanRGBT stack does not publish which type its ``ffc_status`` is):

- ``diagnostic_msgs/msg/DiagnosticArray``, as this project's FFC status node publishes it: a status whose values
  hold the key ``ffc_status``; the stamp is the array's header stamp;
- ``std_msgs/msg/Bool``: true during an FFC. A Bool has no header: its row is stamped with the header stamp of the
  camera's latest frame logged before it (the status is published per frame, after it), or with its own log
  time when no frame came yet.

Any other type is refused (:class:`StatusTypeError`, one line); a recording without status messages falls back
to the Boson telemetry rows, then to frozen frames (:mod:`.recording`, :mod:`.sync`).
"""
from __future__ import annotations

BOOL = "std_msgs/msg/Bool"
DIAGNOSTIC = "diagnostic_msgs/msg/DiagnosticArray"
ACCEPTED = (BOOL, DIAGNOSTIC)


class StatusTypeError(Exception):
    """A status topic of a type this reader does not know; one line (without the file and topic)."""


def normalise(schema_name: str) -> str:
    """``pkg/msg/Type`` for ``pkg/msg/Type`` or ``pkg/Type``."""
    parts = schema_name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else schema_name


def check_type(schema_name: str) -> str:
    """The normalised type, or :class:`StatusTypeError` when it is not one of :data:`ACCEPTED`."""
    t = normalise(schema_name)
    if t not in ACCEPTED:
        raise StatusTypeError(f"FFC status of type {schema_name or '(none)'}; expected {' or '.join(ACCEPTED)} "
                              f"(true during FFC); leave the status topic out of a --topics map to detect FFC "
                              f"from frozen frames instead")
    return t


def rows(type_name: str, msg, log_ns: int, last_frame_stamp: int | None) -> list[tuple[int, int]]:
    """The ``(stamp ns, ffc_status)`` rows of one decoded status message of type ``type_name``
    (:func:`check_type`'s)."""
    if type_name == BOOL:
        stamp = last_frame_stamp if last_frame_stamp is not None else int(log_ns)
        return [(int(stamp), 2 if bool(msg.data) else 0)]
    stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
    out = []
    for st in msg.status:
        values = {kv.key: kv.value for kv in st.values}
        if "ffc_status" in values:
            try:
                out.append((stamp, int(values["ffc_status"])))
            except ValueError:
                continue
    return out
