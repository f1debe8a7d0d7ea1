"""cdr.diagnostic_array and cdr.bool_message, the FFC status readers of the index: messages serialised by rosbags (an
independent writer), little- and big-endian, read back field for field; mcap_ros2's decoder (what the index used
before) gives the same fields; a message cut short is one ValueError, never another exception."""
from __future__ import annotations

import pickle

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from platform_tools.dataset import ffcstatus
from platform_tools.dataset.cdr import bool_message, diagnostic_array

TS = get_typestore(Stores.ROS2_HUMBLE)
M = TS.types
text = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\0"), max_size=12)
key_values = st.lists(st.tuples(text, text), max_size=6)
statuses = st.lists(st.tuples(st.integers(0, 3), text, text, text, key_values), max_size=4)


def _array(sec, nanosec, frame_id, status):
    return M["diagnostic_msgs/msg/DiagnosticArray"](
        header=M["std_msgs/msg/Header"](stamp=M["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec),
                                        frame_id=frame_id),
        status=[M["diagnostic_msgs/msg/DiagnosticStatus"](
            level=level, name=name, message=message, hardware_id=hw,
            values=[M["diagnostic_msgs/msg/KeyValue"](key=k, value=v) for k, v in values])
            for level, name, message, hw, values in status])


def _fields(m):
    return (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id,
            [(int(s.level), s.name, s.message, s.hardware_id, [(kv.key, kv.value) for kv in s.values])
             for s in m.status])


@settings(max_examples=150, deadline=None)
@given(sec=st.integers(-2**31, 2**31 - 1), nanosec=st.integers(0, 999_999_999), frame_id=text, status=statuses,
       little=st.booleans())
def test_a_diagnostic_array_reads_back_as_rosbags_wrote_it(sec, nanosec, frame_id, status, little):
    msg = _array(sec, nanosec, frame_id, status)
    data = bytes(TS.serialize_cdr(msg, "diagnostic_msgs/msg/DiagnosticArray", little_endian=little))
    assert _fields(diagnostic_array(data)) == _fields(msg)
    assert _fields(diagnostic_array(memoryview(data))) == _fields(msg)     # as a chunk's slice gives it


@pytest.mark.parametrize("little", [True, False])
@pytest.mark.parametrize("value", [True, False])
def test_a_bool_reads_back(value, little):
    data = bytes(TS.serialize_cdr(M["std_msgs/msg/Bool"](data=value), "std_msgs/msg/Bool", little_endian=little))
    assert bool_message(data).data is value


def test_the_fields_are_the_ones_mcap_ros2_decodes():
    from mcap_ros2._dynamic import generate_dynamic
    msg = _array(1_700_000_123, 456, "thermal_left_optical",
                 [(0, "thermal_left", "ok", "900001", [("ffc_status", "2"), ("clock_step_ns", "-5000000")]),
                  (1, "thermal_right", "", "", [("ffc_status", "0")])])
    data = bytes(TS.serialize_cdr(msg, "diagnostic_msgs/msg/DiagnosticArray"))
    schema = "\n".join(["std_msgs/Header header", "DiagnosticStatus[] status", "=" * 80,
                        "MSG: std_msgs/Header", "builtin_interfaces/Time stamp", "string frame_id", "=" * 80,
                        "MSG: builtin_interfaces/Time", "int32 sec", "uint32 nanosec", "=" * 80,
                        "MSG: diagnostic_msgs/DiagnosticStatus", "byte level", "string name", "string message",
                        "string hardware_id", "KeyValue[] values", "=" * 80,
                        "MSG: diagnostic_msgs/KeyValue", "string key", "string value"])
    decoded = generate_dynamic("diagnostic_msgs/msg/DiagnosticArray", schema)["diagnostic_msgs/msg/DiagnosticArray"](data)
    assert _fields(diagnostic_array(data)) == _fields(decoded)
    ours = diagnostic_array(data)
    assert ffcstatus.rows(ffcstatus.DIAGNOSTIC, ours, 0, None) == ffcstatus.rows(ffcstatus.DIAGNOSTIC, decoded, 0, None)
    assert ffcstatus.clock_step_values(ours) == {1_700_000_123_000_000_456: -5_000_000}


def test_every_message_cut_short_is_one_value_error():
    msg = _array(7, 8, "f", [(2, "thermal_left", "FFC", "x", [("ffc_status", "2"), ("k", "v")])])
    data = bytes(TS.serialize_cdr(msg, "diagnostic_msgs/msg/DiagnosticArray"))
    for n in range(len(data)):
        with pytest.raises(ValueError):
            diagnostic_array(data[:n])
    with pytest.raises(ValueError):
        bool_message(b"\0\1\0\0")
    huge = bytearray(data)
    assert huge[20:24] == (1).to_bytes(4, "little")      # the status count: after stamp and frame_id "f\0", aligned
    huge[20:24] = (2**31).to_bytes(4, "little")          # far past the data
    with pytest.raises(ValueError):
        diagnostic_array(bytes(huge))


ffc_values = st.lists(st.tuples(st.sampled_from(["ffc_status", "clock_step_ns", "other"]),
                                st.one_of(st.integers(-10**12, 10**12).map(str), text)), max_size=5)


@settings(max_examples=150, deadline=None)
@given(sec=st.integers(0, 2**31 - 1), nanosec=st.integers(0, 999_999_999),
       status=st.lists(st.tuples(st.integers(0, 3), text, text, text, ffc_values), max_size=4),
       log_ns=st.integers(0, 2**62), last=st.one_of(st.none(), st.integers(0, 2**62)))
def test_what_the_workers_send_back_gives_the_rows_the_whole_message_gives(sec, nanosec, status, log_ns, last):
    # ffcstatus.read runs in the export's workers; the rows and clock steps made of it are those of the message
    data = bytes(TS.serialize_cdr(_array(sec, nanosec, "f", status), "diagnostic_msgs/msg/DiagnosticArray"))
    whole = diagnostic_array(data)
    got = ffcstatus.read(ffcstatus.DIAGNOSTIC, memoryview(data))
    assert pickle.loads(pickle.dumps(got)) == got
    assert ffcstatus.rows_of(got, log_ns, last) == ffcstatus.rows(ffcstatus.DIAGNOSTIC, whole, log_ns, last)
    assert dict(got.clock_steps) == ffcstatus.clock_step_values(whole)
    # and what they are, from the values hypothesis drew: each status's last ffc_status, where it is a whole number
    stamp, want = sec * 1_000_000_000 + nanosec, []
    for *_, values in status:
        last_ffc = [v for k, v in values if k == "ffc_status"][-1:]
        for v in last_ffc:
            try:
                want.append((stamp, int(v)))
            except ValueError:
                pass
    assert ffcstatus.rows_of(got, log_ns, last) == want


@pytest.mark.parametrize("value", [True, False])
@pytest.mark.parametrize("last", [None, 123_456_789])
def test_a_bool_read_by_a_worker_is_stamped_by_its_frame_here(value, last):
    data = bytes(TS.serialize_cdr(M["std_msgs/msg/Bool"](data=value), "std_msgs/msg/Bool"))
    got = ffcstatus.read(ffcstatus.BOOL, data)
    assert ffcstatus.rows_of(got, 99, last) == ffcstatus.rows(ffcstatus.BOOL, bool_message(data), 99, last)
    assert ffcstatus.rows_of(got, 99, last) == [(99 if last is None else last, 2 if value else 0)]
    with pytest.raises(ValueError):
        ffcstatus.read(ffcstatus.BOOL, data[:4])
