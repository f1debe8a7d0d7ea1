"""The client, the sync set-up and the camera operations on bytes, through the in-memory loopback
transport: no pty, no thread, no timing but the timeouts asked for."""
from __future__ import annotations

import pytest

from platform_tools.boson import codes, fslp, operations as ops, syncsetup, transaction
from platform_tools.boson import commands as C
from platform_tools.boson.client import BosonClient, Timeouts
from platform_tools.boson.emulator import BosonState, answer_with
from platform_tools.boson.loopback import LoopbackTransport

FAST = Timeouts(first_s=0.02, rest_s=0.02, slow_s=0.05, reopen_s=0.1)


def client_for(respond, retries: int = 3) -> tuple[BosonClient, LoopbackTransport]:
    port = LoopbackTransport(respond)
    return BosonClient(port, timeouts=FAST, retries=retries, backoff_s=0.0).open(), port


def camera(serial: int = 93588, **state) -> tuple[BosonClient, LoopbackTransport, BosonState]:
    s = BosonState(serial, **state)
    client, port = client_for(answer_with(s))
    return client, port, s


def scripted(*answers):
    """A responder that answers the n-th request with answers[n](request frame) (bytes chunks)."""
    decoder, calls = fslp.StreamDecoder(), []

    def respond(data: bytes) -> list[bytes]:
        (req,) = decoder.feed(data)
        calls.append(req)
        return answers[min(len(calls), len(answers)) - 1](req)
    respond.calls = calls
    return respond


def ok(payload: bytes):
    return lambda req: [fslp.encode(fslp.reply(req, 0, payload))]


SN = (93588).to_bytes(4, "big")


def test_a_request_is_one_fslp_frame_and_its_reply_is_decoded():
    client, port, _ = camera()
    assert client.call(C.GET_CAMERA_SN) == 93588
    (frame,) = fslp.StreamDecoder().feed(port.written[0])
    assert (frame.function_id, frame.sequence, frame.is_request) == (C.GET_CAMERA_SN.function_id, 1, True)


def test_a_stale_reply_is_discarded_and_the_matching_one_taken():
    stale = lambda req: [fslp.encode(fslp.Frame(req.channel, fslp.next_sequence(req.sequence + 5),  # noqa: E731
                                                req.function_id, 0, b"\0\0\0\1")),
                         fslp.encode(fslp.reply(req, 0, SN))]
    client, _ = client_for(scripted(stale))
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.stats.discarded == 1 and client.stats.retries == 0


def test_a_reply_split_into_single_bytes_is_reassembled():
    client, _ = client_for(lambda data: [bytes([b]) for b in fslp.encode(
        fslp.reply(fslp.StreamDecoder().feed(data)[0], 0, SN))])
    assert client.call(C.GET_CAMERA_SN) == 93588


def test_busy_then_ok_is_retried_with_a_new_sequence_number():
    respond = scripted(lambda req: [fslp.encode(fslp.reply(req, 0x283))], ok(SN))
    client, _ = client_for(respond)
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.stats.retries == 1 and [r.sequence for r in respond.calls] == [1, 2]


def test_a_corrupt_reply_counts_as_a_bad_frame_and_is_retried():
    def corrupt(req):
        rep = fslp.reply(req, 0, SN)
        return [fslp.encode(rep, crc=fslp.crc16(fslp.encode_body(rep)[:-2]) ^ 0x5A5A)]
    client, _ = client_for(scripted(corrupt, ok(SN)))
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.stats.bad_frames == 1 and client.stats.retries == 1


def test_no_answer_gives_up_after_every_retry():
    client, port = client_for(lambda data: [], retries=2)
    with pytest.raises(codes.ReplyTimeout, match="gave up after 3 attempts"):
        client.call(C.GET_CAMERA_SN)
    assert len(port.written) == 3


def test_a_camera_error_is_raised_by_name_without_retry():
    client, port, _ = camera()
    with pytest.raises(codes.RangeError):
        client.call(C.SET_EXT_SYNC, 7)
    assert len(port.written) == 1


def test_a_vanished_port_is_reopened_and_the_command_sent_again():
    client, port, _ = camera()
    port.vanish()
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.stats.reopens == 1 and port.reopens == 1


def test_camera_info_reads_the_table_and_checks_the_serial():
    client, _, state = camera(fpa_temp_c_x10=-153)
    info = ops.camera_info(client, 93588)
    assert info["serial"] == 93588 and info["fpa_temp_c"] == -15.3 and info["sync_mode"] == "disable"
    assert "error" not in info
    assert ops.camera_info(client, 11111, ("serial",))["error"] == "answers as SN 93588, not SN 11111"


def configure_one(client, serial, plan, path):
    return transaction.configure_rig([transaction.Member(client, serial, syncsetup.CameraResult("left", path))],
                                     plan)[0]


def test_sync_setup_on_bytes_configures_then_finds_nothing_to_do(rig):
    plan = syncsetup.plan_for(rig, mode="slave", persist=False)
    client, port, state = camera()
    first = configure_one(client, 93588, plan, port.path)
    assert first.status == "configured" and state.settings["ext_sync_mode"] == int(C.ExtSyncMode.SLAVE)
    assert [c["setting"] for c in first.changes][0] == "ext_sync_mode"
    again = configure_one(client, 93588, plan, port.path)
    assert again.status == "unchanged" and again.changes == []


def test_sync_setup_refuses_a_camera_with_another_serial(rig):
    client, port, state = camera(11111)
    result = configure_one(client, 93588, syncsetup.plan_for(rig, mode="slave", persist=False), port.path)
    assert result.status == "error" and "SN 11111" in result.error
    assert state.settings["ext_sync_mode"] == int(C.ExtSyncMode.DISABLE)      # nothing written


def test_ffc_mode_is_written_only_when_it_differs():
    client, port, _ = camera()
    assert ops.set_ffc_mode(client, "manual") == {"before": "auto", "ffc_mode": "manual"}
    writes = len(port.written)
    assert ops.set_ffc_mode(client, "manual") == {"before": "manual", "ffc_mode": "manual"}
    assert len(port.written) == writes + 2          # two reads, no write


def test_raw_call_reports_a_camera_error_in_the_row():
    client, _, _ = camera()
    row = ops.raw_call(client, 0x00051234, b"")
    assert row["status"] == "0x161" and "error" in row
    assert ops.raw_call(client, C.GET_CAMERA_SN.function_id, b"")["value"] == 93588


def test_a_plan_that_cannot_be_done_is_one_line(rig):
    with pytest.raises(ValueError, match="applies to --slave"):
        syncsetup.plan_for(rig, mode="master", check_trigger_s=0.5)
    with pytest.raises(ValueError, match="use it with --persist"):
        syncsetup.plan_for(rig, persist=False, reboot_verify=True)
    assert syncsetup.plan_for(rig, mode="slave", check_trigger_s=0.5).check_trigger.rate_hz == rig.desc.sync.rate_hz


def test_noise_holding_the_start_byte_before_the_reply_is_skipped_without_a_retry():
    noise = bytes([0x01, fslp.START, 0x02, 0x03, fslp.START, 0x55])      # two false starts
    client, _ = client_for(scripted(lambda req: [noise + fslp.encode(fslp.reply(req, 0, SN))]))
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.stats.retries == 0 and client.stats.bad_frames == 2


def test_noise_in_its_own_chunk_before_the_reply_is_skipped_too():
    noise = bytes([0x10, fslp.START, 0x20])
    client, _ = client_for(scripted(lambda req: [noise, fslp.encode(fslp.reply(req, 0, SN))]))
    assert client.call(C.GET_CAMERA_SN) == 93588 and client.stats.retries == 0


def test_error_replies_carry_the_payload_size_the_sdk_reads():
    from platform_tools.boson.emulator.state import error_payload
    s = BosonState(93588)
    respond = answer_with(s)
    (raw,) = respond(fslp.request(1, C.GET_EXT_SYNC.function_id, b"\0"))     # excess bytes: an error
    frame = fslp.decode(raw)
    assert frame.status == 0x17E and frame.payload == bytes(4) == error_payload(C.GET_EXT_SYNC.function_id)
    assert error_payload(C.SET_EXT_SYNC.function_id) == b""


def test_every_setter_has_a_getter_that_reads_back_what_it_set():
    client, _, state = camera()
    setters = [c for c in C.BY_NAME.values() if c.request and "Set" in c.name]
    for setter in setters:
        getter = C.BY_NAME[setter.name.replace("Set", "Get", 1)]
        value = 1
        client.call(setter, value)
        assert int(client.call(getter)) == value, setter.name



def test_a_late_reply_answers_its_call_and_the_reply_owed_to_the_retry_is_drained():
    """A camera slower than the timeout, working through its requests in order: the first attempt gets
    no reply in time, the retry is sent, then the camera answers both. The first reply answers the call;
    the second (owed to the retry) is read before the call returns, so the next command is not sent
    behind it and finds no stale reply."""
    state = BosonState(93588)
    respond, held = answer_with(state), []

    def slow(data: bytes) -> list[bytes]:
        (req,) = fslp.StreamDecoder().feed(data)
        if req.sequence == 1:
            held.append(data)                 # still working on it when the first-byte timeout passes
            return []
        out = [c for d in held for c in respond(d)] + list(respond(data))
        held.clear()
        return out
    client, port = client_for(slow)
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert (client.stats.timeouts, client.stats.retries, client.stats.drained) == (1, 1, 1)
    assert client.call(C.GET_CAMERA_PN) == "20640000EMULATED"
    assert (client.stats.timeouts, client.stats.discarded, len(port.written)) == (1, 0, 3)

def test_the_serial_is_asked_once_per_opening_of_the_port():
    client, port, _ = camera()
    assert client.camera_serial() == client.camera_serial() == 93588
    assert len(port.written) == 1
    port.vanish()
    client.call(C.GET_EXT_SYNC)            # the port re-opened: another camera may be there now
    assert client.camera_serial() == 93588 and len(port.written) == 3     # SN, GetExtSyncMode, SN again


def test_the_set_up_spends_no_round_trip_an_earlier_read_settles(rig):
    """Serial (once), four settings read, three written, the three written read back: 11 requests; a second
    run writes nothing and reads each setting once."""
    plan = syncsetup.plan_for(rig, mode="slave", persist=False)
    client, port, state = camera()
    first = configure_one(client, 93588, plan, port.path)
    assert first.status == "configured" and first.link["requests"] == len(port.written) == 11
    names = [C.BY_ID[fslp.StreamDecoder().feed(w)[0].function_id].name for w in port.written]
    assert names.count("bosonGetCameraSN") == 1 and names.count("telemetryGetPacking") == 1
    assert sum(n.startswith(("bosonSet", "telemetrySet")) for n in names) == 3
    again = configure_one(client, 93588, plan, port.path)
    assert again.status == "unchanged" and len(port.written) == 11 + 4
    assert {k: int(v) for k, v in first.after.items()} == {k: state.settings[k] for k in first.after}


def test_the_pool_keeps_one_client_per_port_and_closes_the_ports_it_will_not_use():
    from platform_tools.boson.discovery import Target
    opened = []

    def opener(target, timeouts, retries):
        client, _, _ = camera()
        opened.append(target.port)
        return client
    with ops.ClientPool(FAST, 1, opener=opener) as pool:
        a = pool.open(Target("/dev/a", "/dev/a", None))
        assert a.camera_serial() == 93588
        again = pool.open(Target("left", "/dev/a", 93588))      # identity's client, relabelled
        assert again is a and a.label == "left" and a.requests == 1
        b = pool.open(Target("/dev/b", "/dev/b", None))
        pool.keep(p for p in ["/dev/a"])                         # /dev/b holds a camera the command leaves alone
        assert a.transport.is_open and not b.transport.is_open
        assert pool.open(Target("b", "/dev/b", None)) is not b and opened == ["/dev/a", "/dev/b", "/dev/b"]
    assert not a.transport.is_open


def test_a_port_that_vanishes_while_owed_replies_are_drained_still_answers_the_call():
    """The late reply arrives, then the camera re-enumerates before its reply to the duplicate: the call
    is answered, and the next command re-opens the port."""
    state = BosonState(93588)
    respond, held = answer_with(state), []

    def slow(data: bytes) -> list[bytes]:
        (req,) = fslp.StreamDecoder().feed(data)
        if req.sequence == 1:
            held.append(data)
            return []
        if held:                                           # the retry: only the late reply comes back
            out = [c for d in held for c in respond(d)]
            held.clear()
            port.gone_after_reply = True
            return out
        return list(respond(data))
    client, port = client_for(slow)
    port.gone_after_reply = False
    loop_read = port.read

    def read(timeout_s):
        if port.gone_after_reply and not port._pending:    # the reply was read: now the port vanishes
            port.gone_after_reply = False
            port.vanish()
        return loop_read(timeout_s)
    port.read = read
    assert client.call(C.GET_CAMERA_SN) == 93588           # answered; the drain stopped at the vanished port
    assert client.stats.drained == 0 and client.stats.reopens == 0
    assert client.call(C.GET_EXT_SYNC) is C.ExtSyncMode.DISABLE and client.stats.reopens == 1
