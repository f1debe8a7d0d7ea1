"""FSLP on bytes: golden frames from the reference, CRC check value, escaping, round trips, and a
decoder that raises only its own errors whatever it is fed."""
from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings, strategies as st

from platform_tools.boson import fslp

GET_SN_SEQ1 = bytes.fromhex("8E 00 00000001 00050002 FFFFFFFF 01 0B AE".replace(" ", ""))
SET_SLAVE_SEQ1 = bytes.fromhex("8E 00 00000001 00050098 FFFFFFFF 00000002 A5 D3 AE".replace(" ", ""))
WRITE_FLASH_SEQ3 = bytes.fromhex("8E 00 00000003 00050018 FFFFFFFF 85 98 AE".replace(" ", ""))


def test_crc_check_value():
    assert fslp.crc16(b"123456789") == 0xE5CC


def test_golden_get_camera_sn_request_captured_from_a_camera():
    assert fslp.request(1, 0x00050002) == GET_SN_SEQ1
    f = fslp.decode(GET_SN_SEQ1)
    assert (f.channel, f.sequence, f.function_id, f.status, f.payload) == (0, 1, 0x00050002, 0xFFFFFFFF, b"")


def test_golden_get_camera_sn_reply_payload_is_serial_93588():
    from platform_tools.boson import commands as C
    reply = fslp.encode(fslp.Frame(0, 1, 0x00050002, 0, bytes.fromhex("00016D94")))
    f = fslp.decode(reply)
    assert f.status == 0 and C.GET_CAMERA_SN.decode_reply(f.payload) == 93588


def test_computed_frames_from_the_reference():
    assert fslp.request(1, 0x00050098, struct.pack(">i", 2)) == SET_SLAVE_SEQ1
    assert fslp.request(3, 0x00050018) == WRITE_FLASH_SEQ3


def test_escaping_covers_header_payload_and_crc():
    # sequence 0x8E, payload with all three specials: none may appear raw between START and END
    frame = fslp.Frame(0, 0x8E, 0x00050002, 0xAE9E8E00, bytes([0x8E, 0x9E, 0xAE, 0x01]))
    raw = fslp.encode(frame)
    inner = raw[1:-1]
    assert fslp.START not in inner and fslp.END not in inner
    assert bytes([0x9E, 0x81]) in inner and bytes([0x9E, 0x91]) in inner and bytes([0x9E, 0xA1]) in inner
    assert fslp.decode(raw) == frame


def test_crc_bytes_are_escaped_too():
    # find a payload whose CRC contains a special byte, and check it is escaped
    for i in range(5000):
        frame = fslp.Frame(0, 1, 0x00050002, 0, i.to_bytes(4, "big"))
        crc = fslp.encode_body(frame)[-2:]
        if any(b in fslp.SPECIAL for b in crc):
            raw = fslp.encode(frame)
            assert fslp.START not in raw[1:-1] and fslp.END not in raw[1:-1]
            assert fslp.decode(raw) == frame
            return
    pytest.fail("no CRC with a special byte found")


def test_bad_crc_is_an_error_not_a_log_line():
    raw = bytearray(GET_SN_SEQ1)
    raw[-2] ^= 0x01
    with pytest.raises(fslp.CrcError):
        fslp.decode(bytes(raw))


@pytest.mark.parametrize("raw", [b"", b"\x8e\xae", b"\x8e\x00\xae", GET_SN_SEQ1[:-1], b"\x00" + GET_SN_SEQ1[1:],
                                 b"\x8e\x9e\x00\xae", b"\x8e\x9e\xae"])
def test_malformed_frames(raw):
    with pytest.raises(fslp.FramingError):
        fslp.decode(raw)


def test_sequence_numbers_skip_special_bytes():
    assert fslp.next_sequence(1) == 2
    assert fslp.next_sequence(0x8D) == 0x8F
    assert fslp.next_sequence(0x9D) == 0x9F
    assert fslp.next_sequence(0xAD) == 0xAF
    assert fslp.next_sequence(0x8DFFFF) == 0x8F0000
    assert fslp.next_sequence(0xFFFFFFFF) == 1
    seq, seen = 0, set()
    for _ in range(3000):
        seq = fslp.next_sequence(seq)
        assert not fslp.has_special_byte(seq) and seq not in seen
        seen.add(seq)


frames = st.builds(fslp.Frame, st.integers(0, 255), st.integers(0, 2**32 - 1), st.integers(0, 2**32 - 1),
                   st.integers(0, 2**32 - 1), st.binary(max_size=300))


@settings(max_examples=300, deadline=None)
@given(frames)
def test_round_trip(frame):
    assert fslp.decode(fslp.encode(frame)) == frame


@settings(max_examples=150, deadline=None)
@given(st.lists(frames, min_size=1, max_size=5), st.data())
def test_stream_decoder_reassembles_any_chunking(frame_list, data):
    stream = b"".join(fslp.encode(f) for f in frame_list)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    dec = fslp.StreamDecoder()
    got = []
    for a, b in zip([0] + cuts, cuts + [len(stream)]):
        got += dec.feed(stream[a:b])
    assert got == frame_list


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=400))
def test_decoder_raises_only_its_own_errors(raw):
    try:
        fslp.decode(raw)
    except fslp.FslpError:
        pass
    for item in fslp.StreamDecoder().feed(raw):
        assert isinstance(item, (fslp.Frame, fslp.FslpError))


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=60), frames)
def test_stream_decoder_recovers_after_noise(noise, frame):
    dec = fslp.StreamDecoder()
    dec.feed(noise)
    out = dec.feed(fslp.encode(frame))
    assert out[-1] == frame


def test_encoder_and_decoder_share_one_body_limit():
    CRC_SIZE, HEADER_SIZE, MAX_BODY = fslp.CRC_SIZE, fslp.HEADER_SIZE, fslp.MAX_BODY
    longest = fslp.Frame(0, 1, 2, 0, bytes(MAX_BODY - HEADER_SIZE - CRC_SIZE))
    assert fslp.decode(fslp.encode(longest)) == longest
    with pytest.raises(ValueError):
        fslp.encode(fslp.Frame(0, 1, 2, 0, bytes(MAX_BODY - HEADER_SIZE - CRC_SIZE + 1)))
    body = bytes(MAX_BODY - CRC_SIZE + 1)           # one byte over, hand-built with a valid CRC
    raw = bytes([0x8E]) + fslp.escape(body + fslp.crc16(body).to_bytes(2, "big")) + bytes([0xAE])
    with pytest.raises(fslp.FramingError, match="limit"):
        fslp.decode(raw)
    assert isinstance(fslp.StreamDecoder().feed(raw)[0], fslp.FramingError)
