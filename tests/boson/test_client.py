"""The client against an emulated Boson over a real pty with pyserial: faults recovered or reported,
stale replies discarded, re-open after a reboot, flash that survives it, a trigger-driven counter."""
from __future__ import annotations

import os
import time

import pytest

from platform_tools.boson import codes, commands as C
from platform_tools.boson.client import BosonClient, Timeouts
from platform_tools.boson.emulator import parse_faults
from platform_tools.boson.transport import SerialTransport

FAST = Timeouts(first_s=0.15, rest_s=0.3, slow_s=0.5, reopen_s=3.0)


@pytest.fixture
def boson(make_boson):
    emu = make_boson()
    client = BosonClient(SerialTransport(emu.port), timeouts=FAST, retries=3, backoff_s=0.005).open()
    yield emu, client
    client.close()


@pytest.mark.slow
@pytest.mark.parametrize("fault", ["busy:times=2", "notready:times=3", "badcrc:times=1", "drop:times=2",
                                   "split", "wrongseq", "garbage", "stall:times=1", "reboot:times=1"])
def test_faults_are_recovered(boson, fault):
    emu, client = boson
    emu.faults = parse_faults(fault)
    assert client.call(C.GET_CAMERA_SN) == 93588
    assert client.call(C.GET_CAMERA_PN) == "20640000EMULATED"
    if fault.startswith("wrongseq"):
        assert client.stats.discarded >= 1
    if fault.startswith(("badcrc", "drop")):
        assert client.stats.bad_frames >= 1 and client.stats.retries >= 1
    if fault.startswith("reboot"):
        assert client.stats.reopens == 1 and emu.state.boots == 2


def test_persistent_busy_is_reported_by_name(boson):
    emu, client = boson
    emu.faults = parse_faults("busy")
    with pytest.raises(codes.CamBusy, match="0x283"):
        client.call(C.SET_EXT_SYNC, "slave")
    assert client.stats.retries == 3


@pytest.mark.slow
def test_camera_that_stops_answering_times_out(boson):
    emu, client = boson
    emu.faults = parse_faults("stall")
    with pytest.raises(codes.ReplyTimeout, match="gave up after 4 attempts"):
        client.call(C.GET_CAMERA_SN)
    assert emu.requests == 4


def test_persistent_garbage_is_a_bad_reply(boson):
    emu, client = boson
    emu.faults = parse_faults("badcrc")
    with pytest.raises(codes.BadReply):
        client.call(C.GET_CAMERA_SN)


def test_range_error_is_not_retried(boson):
    emu, client = boson
    with pytest.raises(codes.RangeError):
        client.call(C.SET_EXT_SYNC, 7)
    assert client.stats.retries == 0


def test_unknown_function_id(boson):
    _, client = boson
    with pytest.raises(codes.BadCommandId):
        client.call_raw(0x00051234)


def test_sequence_numbers_increase(boson):
    emu, client = boson
    seqs = []
    for _ in range(3):
        client.call(C.GET_CAMERA_SN)
        seqs.append(client._seq)
    assert seqs == sorted(seqs) and len(set(seqs)) == 3


def test_flash_survives_reboot_and_ram_does_not(boson):
    emu, client = boson
    client.call(C.SET_GAIN_MODE, "low")
    client.call(C.SET_EXT_SYNC, "slave")
    client.call(C.WRITE_FLASH)
    client.call(C.SET_GAIN_MODE, "auto")       # RAM only
    client.reboot()
    assert emu.state.boots == 2
    assert client.call(C.GET_EXT_SYNC) is C.ExtSyncMode.SLAVE
    assert client.call(C.GET_GAIN_MODE) is C.GainMode.LOW
    assert os.readlink(emu.link) == emu.path             # the by-id link follows the new pty


@pytest.mark.slow
def test_frame_counter_advances_only_with_trigger_in_slave(boson, trigger):
    emu, client = boson
    a = client.call(C.GET_FRAME_COUNT)
    time.sleep(0.1)
    assert client.call(C.GET_FRAME_COUNT) > a            # free running
    client.call(C.SET_EXT_SYNC, "slave")
    a = client.call(C.GET_FRAME_COUNT)
    time.sleep(0.15)
    assert client.call(C.GET_FRAME_COUNT) == a           # slave, no trigger: no frames
    t0 = time.monotonic()
    trigger.start()
    time.sleep(0.3)
    b = client.call(C.GET_FRAME_COUNT)
    elapsed = time.monotonic() - t0
    assert 30 * elapsed - 2 <= b - a <= 30 * elapsed + 1  # 30 Hz pulses, one frame each
    trigger.stop()
    c = client.call(C.GET_FRAME_COUNT)
    time.sleep(0.1)
    assert client.call(C.GET_FRAME_COUNT) == c


def test_ffc_runs_and_completes(boson):
    emu, client = boson
    emu.state.ffc_duration_s = 0.1
    assert client.call(C.GET_FFC_STATUS) is C.FfcStatus.NONE
    client.call(C.RUN_FFC)
    assert client.call(C.GET_FFC_STATUS) is C.FfcStatus.IN_PROGRESS
    assert client.call(C.GET_FFC_IN_PROGRESS) == 1
    time.sleep(0.15)
    assert client.call(C.GET_FFC_STATUS) is C.FfcStatus.COMPLETE


def test_negative_fpa_temperature_over_the_wire(make_boson):
    emu = make_boson(777, fpa_temp_c_x10=-153)
    with BosonClient(SerialTransport(emu.port), timeouts=FAST) as client:
        assert client.call(C.GET_FPA_TEMP_C) == -153


def test_port_that_never_comes_back(boson):
    emu, client = boson
    emu.boot_s = 10.0
    emu.faults = parse_faults("reboot:times=1")
    client.timeouts = Timeouts(first_s=0.15, rest_s=0.3, slow_s=0.5, reopen_s=0.4)
    with pytest.raises(codes.PortGone, match="did not come back"):
        client.call(C.GET_CAMERA_SN)


@pytest.mark.slow
def test_a_slow_camera_costs_its_latency_not_a_timeout_per_command(boson):
    emu, client = boson
    emu.faults = parse_faults("delay:s=0.4")        # every reply 0.4 s late; the first-byte timeout is 0.15 s
    assert client.call(C.GET_CAMERA_SN) == 93588
    # the first call times out while the reply is on its way (0.4 s: two attempts of 0.15 s, a third
    # sent); the late reply answers it and the replies owed to the later attempts are drained
    learned = client.stats.timeouts
    assert 1 <= learned <= 2 and client.stats.drained == client.stats.retries and client.latency_s > 0.15
    for _ in range(5):
        assert client.call(C.GET_CAMERA_SN) == 93588
    # a timeout per command (the reply always later than the timeout, the late one dropped) would give at
    # least one retry per call; here none after the first call, and the camera got no request twice
    assert client.stats.timeouts == learned and emu.requests == 6 + client.stats.retries
