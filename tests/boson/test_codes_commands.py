"""FLR_RESULT codes map to named errors; the command table encodes and decodes both ways."""
from __future__ import annotations

import struct

import pytest
from hypothesis import given, strategies as st

from platform_tools.boson import codes, commands as C
from platform_tools.boson.emulator.faults import FaultRule, parse_faults


def test_every_result_code_has_its_own_named_error():
    names = set()
    for code, (name, _) in codes.RESULTS.items():
        err = codes.error_for(code, "bosonGetCameraSN", "left")
        assert type(err).__name__ == name and err.code == code
        assert isinstance(err, codes.CameraError) and isinstance(err, codes.BosonError)
        assert f"0x{code:03X}" in str(err) and "left" in str(err) and "bosonGetCameraSN" in str(err)
        names.add(name)
    assert len(names) == len(codes.RESULTS)
    for code in (0x131, 0x132, 0x161, 0x162, 0x170, 0x17D, 0x17E, 0x17F, 0x181, 0x1B0, 0x201, 0x202, 0x203,
                 0x207, 0x283, *range(0x708, 0x70F)):
        assert code in codes.ERRORS


def test_transient_codes_and_unknown_codes():
    assert codes.error_for(0x283).transient and codes.error_for(0x202).transient
    assert not codes.error_for(0x203).transient
    assert isinstance(codes.error_for(0x283), codes.CamBusy)
    unknown = codes.error_for(0x7777)
    assert isinstance(unknown, codes.UnknownResult) and unknown.code == 0x7777
    with pytest.raises(ValueError):
        codes.error_for(0)


def test_ids_from_the_reference():
    expected = {"bosonGetCameraSN": 0x00050002, "bosonSetExtSyncMode": 0x00050098,
                "bosonGetExtSyncMode": 0x00050099, "bosonGetFfcStatus": 0x00050054,
                "bosonGetFFCInProgress": 0x0005000C, "bosonWriteDynamicHeaderToFlash": 0x00050018,
                "bosonGetISPFrameCount": 0x000500AC, "bosonReboot": 0x00050010}
    for name, fid in expected.items():
        assert C.BY_NAME[name].function_id == fid


@pytest.mark.slow
@given(st.integers(-2**31, 2**31 - 1))
def test_i32_request_round_trip(value):
    payload = C.SET_EXT_SYNC.encode_request(value)
    assert payload == struct.pack(">i", value) and C.SET_EXT_SYNC.decode_request(payload) == (value,)


def test_enums_by_name_and_value():
    assert C.SET_EXT_SYNC.encode_request("slave") == b"\x00\x00\x00\x02"
    assert C.SET_EXT_SYNC.encode_request(C.ExtSyncMode.MASTER) == b"\x00\x00\x00\x01"
    assert C.GET_EXT_SYNC.decode_reply(b"\x00\x00\x00\x02") is C.ExtSyncMode.SLAVE
    assert C.GET_EXT_SYNC.decode_reply(b"\x00\x00\x00\x09") == 9        # unnamed values are kept
    with pytest.raises(ValueError, match="not one of"):
        C.SET_EXT_SYNC.encode_request("sideways")


def test_fpa_temperature_is_signed():
    assert C.GET_FPA_TEMP_C.decode_reply(C.GET_FPA_TEMP_C.encode_reply(-125)) == -125
    assert C.GET_FPA_TEMP_C.decode_reply(b"\xff\x83") == -125


def test_reply_layouts_and_bad_sizes():
    assert C.GET_SOFTWARE_REV.decode_reply(struct.pack(">III", 4, 1, 7)) == (4, 1, 7)
    assert C.GET_CAMERA_PN.decode_reply(b"20640A049-6PAAX\0\0\0\0\0") == "20640A049-6PAAX"
    with pytest.raises(codes.BadReply):
        C.GET_CAMERA_SN.decode_reply(b"\x00\x01")
    with pytest.raises(ValueError):
        C.GET_CAMERA_SN.encode_request(1)


def test_fault_rules():
    rules = parse_faults(["busy:times=2,badcrc:p=0.5", "reboot:fid=0x00050018:n=4"])
    assert [r.kind for r in rules] == ["busy", "badcrc", "reboot"]
    assert rules[2].fid == 0x00050018 and rules[2].n == 4
    import random
    rng = random.Random(1)
    busy = rules[0]
    assert [busy.fires(i, 1, rng) for i in range(1, 5)] == [True, True, False, False]
    reboot = rules[2]
    assert not reboot.fires(4, 0x00050002, rng) and not reboot.fires(3, 0x00050018, rng)
    assert reboot.fires(4, 0x00050018, rng)
    assert parse_faults(rules[2].spec())[0] == FaultRule("reboot", n=4, fid=0x00050018)
    for bad in ("explode", "busy:p=2", "busy:x=1", "busy:times", "busy:n=zero"):
        with pytest.raises(ValueError):
            parse_faults(bad)
