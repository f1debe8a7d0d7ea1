"""The Boson frame counter as pairing evidence (platform_tools.dataset.counters and its use in trigger.py).

Stamps and counters are generated here from the camera's documented behaviour (one count per trigger pulse the
camera receives, a u32 that wraps), independently of the simulator; every pair is checked against the truth
written below."""
from __future__ import annotations

import numpy as np
import pytest

from platform_tools.dataset import counters
from platform_tools.dataset.trigger import TriggerError, assign, reference

P = 1e9 / 30
T0 = 1_700_000_000 * 1_000_000_000


def rig_streams(seed, n=300, latency_ms=10.0, missing=(50, 51, 130, 210), boson_missed=(), zed_step=(0, 0.0),
                thermal_step=(0, 0.0), counter_base=4_294_967_000, zed_drop=0.01, thermal_drop=0.02):
    """(ZED triggers, ZED stamps, thermal triggers, thermal stamps, thermal counters)."""
    rng = np.random.default_rng(seed)
    pulses = [k for k in range(n) if k not in missing]
    kz = np.array([k for k in pulses if rng.random() > zed_drop])
    tz = T0 + kz * P + rng.normal(0, 0.2e6, len(kz))
    received = [k for k in pulses if k not in boson_missed]
    count = {k: counter_base + i for i, k in enumerate(received)}          # the camera counts what it receives
    kt = np.array([k for k in received if rng.random() > thermal_drop])   # the host loses some of them
    tt = T0 + kt * P + latency_ms * 1e6 + rng.normal(0, 0.6e6, len(kt))
    for (at, ms), k, t in ((zed_step, kz, tz), (thermal_step, kt, tt)):
        if ms:
            t += np.where(k >= at, ms * 1e6, 0)
    c = np.array([count[k] for k in kt], np.int64) % (1 << 32)
    return kz, tz.astype(np.int64), kt, tt.astype(np.int64), c


def wrong_pairs(kz, kt, ref, a):
    zk = {int(k): i for i, k in enumerate(ref.trigger)}
    pairs = [(kz[zk[int(T)]], kt[i]) for i, T in enumerate(a.trigger) if int(T) in zk]
    return sum(1 for z, t in pairs if z != t), len(pairs)


# ----------------------------------------------------------------------------- counters.py alone
def test_gaps_are_told_apart_by_the_counter_across_its_wrap():
    # frames at pulses 0 1 2 | 4 (host drop of 3) | 7 (pulses 5, 6 never came) | 8 8 (a repeat) | 9
    counter = np.array([0, 1, 2, 4, 5, 6, 6, 7], np.int64) + (1 << 32) - 3
    trig = np.array([0, 1, 2, 4, 7, 8, 9, 10])
    ts = (T0 + trig * P).astype(np.int64)
    g = counters.classify(ts, counter % (1 << 32), P)
    assert (g.host_drops, g.missing_pulses, g.repeated) == (1, 2, 1)
    assert g.anchor.tolist() == [False, False, False, False, True, False, False, False]
    assert counters.steps_of(counter % (1 << 32)).tolist() == [1, 1, 2, 1, 1, 0, 1]


def test_a_step_interval_is_not_read_as_missing_pulses():
    counter = np.arange(6, dtype=np.int64)
    ts = (T0 + np.arange(6) * P).astype(np.int64)
    ts[3:] += int(2 * P)                         # a clock step of exactly two periods after frame 2
    assert counters.classify(ts, counter, P).missing_pulses == 2
    assert counters.classify(ts, counter, P, {3}).missing_pulses == 0


@pytest.mark.parametrize("change_ms,pulses", [(33.333, True), (66.7, True), (100.0, True), (20.0, False),
                                              (5.0, False), (-33.333, False), (-100.0, False), (250.0, False)])
def test_level_changes_of_whole_periods_are_missing_pulses(change_ms, pulses):
    assert counters.is_missing_pulses(change_ms * 1e6, P) is pulses


# ----------------------------------------------------------------------------- the counter in the pairing
@pytest.mark.parametrize("thermal_step_ms", [5, -5, 20, -20, -100, 250])
def test_a_step_on_the_thermal_clock_alone_is_sized_by_the_counter_without_imu(thermal_step_ms):
    """Without the counter a forward step on one clock is known modulo a period (refused); with it, exact."""
    kz, tz, kt, tt, c = rig_streams(11, thermal_step=(150, thermal_step_ms))
    ref = reference(tz, P)                                            # no IMU
    a = assign(tz, tt, P, camera="thermal_left", window_ms=(0, 30), ref=ref, counter=c)
    wrong, n = wrong_pairs(kz, kt, ref, a)
    assert wrong == 0 and n > 270, (wrong, n)
    (st,) = a.steps
    assert st.exact and st.sized_by == "frame counter"
    assert st.step_ns / 1e6 == pytest.approx(thermal_step_ms, abs=0.5)
    assert a.segments[1].offset_ns / 1e6 == pytest.approx(10 + thermal_step_ms, abs=0.5)
    assert "sized by the frame counter" in a.segments[1].established_by or thermal_step_ms < 0
    if thermal_step_ms > 0 and thermal_step_ms % (1000 / 30) > 2.5:
        with pytest.raises(TriggerError, match="modulo one period"):
            assign(tz, tt, P, camera="thermal_left", window_ms=(0, 30), ref=ref)


@pytest.mark.parametrize("latency_ms", [40.0, 85.0, 190.0])
def test_a_large_offset_is_fixed_by_the_counter_when_the_window_says_nothing(latency_ms):
    """No stated latency (or a wrong one): the counter-classified missing pulses decide, through host drops."""
    for seed in (2, 3, 4):
        kz, tz, kt, tt, c = rig_streams(seed, latency_ms=latency_ms, zed_drop=0.03, thermal_drop=0.05)
        ref = reference(tz, P)
        for window in (None, (0, 30)):
            a = assign(tz, tt, P, camera="thermal_left", window_ms=window, ref=ref, counter=c)
            assert wrong_pairs(kz, kt, ref, a)[0] == 0
            (g,) = a.segments
            assert g.offset_ns / 1e6 == pytest.approx(latency_ms, abs=0.3)
            assert "classified by the frame counter" in g.established_by
            if window and latency_ms > 30:
                assert "outside the rig's stated latency" in g.established_by
        assert a.missing_pulses == 4 and a.counter
        between = set(range(kt[0], kt[-1] + 1)) - {50, 51, 130, 210}      # pulses between the first and last frame
        assert a.host_drops == len(between) - len(kt) > 0                  # every frame lost on the host


def test_the_counter_decides_where_host_drops_blur_the_gaps():
    """85 ms late, no stated latency, 3 % / 5 % host drops: without the counter the host drops blur the gaps
    and 6 of these 10 recordings are refused (never mispaired); with it every one is paired right."""
    refused = 0
    for seed in range(2, 12):
        kz, tz, kt, tt, c = rig_streams(seed, latency_ms=85.0, zed_drop=0.03, thermal_drop=0.05)
        ref = reference(tz, P)
        a = assign(tz, tt, P, camera="thermal_left", window_ms=None, ref=ref, counter=c)
        assert wrong_pairs(kz, kt, ref, a)[0] == 0
        try:
            b = assign(tz, tt, P, camera="thermal_left", window_ms=None, ref=ref)
        except TriggerError as exc:
            assert "no Boson frame counter" in str(exc)
            refused += 1
        else:
            assert wrong_pairs(kz, kt, ref, b)[0] == 0
    assert refused == 6


def test_a_pulse_missed_by_one_boson_alone_is_reported_and_does_not_mislead():
    kz, tz, kt, tt, c = rig_streams(7, latency_ms=40.0, boson_missed=(100,))
    ref = reference(tz, P)
    a = assign(tz, tt, P, camera="thermal_left", window_ms=None, ref=ref, counter=c)
    assert wrong_pairs(kz, kt, ref, a)[0] == 0
    assert a.missing_pulses == 5
    assert "missed by this Boson alone" in a.segments[0].established_by


def test_one_missing_pulse_is_not_enough_alone():
    """A single anchor could be a pulse missed by the Boson alone on a trigger the ZED dropped: not decisive."""
    kz, tz, kt, tt, c = rig_streams(8, latency_ms=85.0, missing=(120,))
    with pytest.raises(TriggerError, match="ambiguous"):
        assign(tz, tt, P, camera="thermal_left", window_ms=None, counter=c)


def test_a_counter_read_from_the_wrong_bytes_is_not_used():
    """telemetry.py's byte layout is still to be checked on a camera: a counter decoded with its 16-bit words
    byte-swapped must be recognised as not a frame counter, never used to steer the pairing."""
    kz, tz, kt, tt, c = rig_streams(5)
    assert counters.implausible(tt, c, P) is None
    swapped = np.frombuffer(c.astype(">u4").tobytes(), ">u2").byteswap().view(">u4").astype(np.int64)
    assert "advances as the stamps do on only" in counters.implausible(tt, swapped, P)
