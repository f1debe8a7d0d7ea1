"""Pairing by trigger (platform_tools.dataset.trigger) on stamps generated here, independently of the
simulator: every thermal frame must pair with the ZED frame of the trigger that exposed it (checked
against the truth written below), or the assignment must fail naming the evidence missing."""
from __future__ import annotations

import numpy as np
import pytest

from platform_tools.dataset.trigger import TriggerError, assign, reference

P = 1e9 / 30
T0 = 1_700_000_000 * 1_000_000_000


def stream(rng, n, off_ms, jit_ms, drop, missing=(), step_at=150, step_ms=0.0):
    k = np.array([i for i in range(n) if rng.random() > drop and i not in missing])
    t = T0 + k * P + off_ms * 1e6 + rng.normal(0, jit_ms * 1e6, len(k))
    t = np.where(k >= step_at, t + step_ms * 1e6, t)
    return k, t.astype(np.int64)


def imu_stamps(n, step_at, step_ms):
    t = T0 + np.arange(int(n * P / 5e6)) * 5e6
    return np.where(t >= T0 + step_at * P - 2e6, t + step_ms * 1e6, t).astype(np.int64)


def wrong_pairs(kz, kt, ref, a):
    zk = {int(k): i for i, k in enumerate(ref.trigger)}
    pairs = [(kz[zk[int(T)]], kt[i]) for i, T in enumerate(a.trigger) if int(T) in zk]
    return sum(1 for z, t in pairs if z != t), len(pairs)


@pytest.mark.slow
@pytest.mark.parametrize("latency_ms", [0.3, 10, 20, 40])
@pytest.mark.parametrize("zed_step,thermal_step", [(0, 0), (-100, 0), (20, 0), (250, 0), (5, 5), (-5, -5),
                                                   (-20, -20), (250, 250)])
@pytest.mark.parametrize("seed", [1, 5, 9])
def test_every_pair_is_the_trigger_that_exposed_it(latency_ms, zed_step, thermal_step, seed):
    rng = np.random.default_rng(seed)
    missing = (50, 51, 130)                       # pulses that never came: missing in every camera
    kz, tz = stream(rng, 300, 0, 0.2, 0.01, missing, step_ms=zed_step)
    kt, tt = stream(rng, 300, latency_ms, 0.6, 0.02, missing, step_ms=thermal_step)
    window = (0, 30) if latency_ms < 30 else (25, 55)
    ref = reference(tz, P, imu_stamps(300, 150, zed_step))
    a = assign(tz, tt, P, camera="thermal_left", window_ms=window, ref=ref)
    wrong, n = wrong_pairs(kz, kt, ref, a)
    assert wrong == 0 and n > 250, (wrong, n)
    for g in a.segments:     # the offset on the first segment's clock is the latency written above
        assert g.established_by
    assert a.segments[0].offset_ns / 1e6 == pytest.approx(latency_ms, abs=0.4)
    if zed_step:
        (st,) = ref.steps
        assert st.exact and st.step_ns / 1e6 == pytest.approx(zed_step, abs=1.0)


@pytest.mark.parametrize("latency_ms", [10, 20, 40])
def test_nearest_stamp_would_mispair_but_the_trigger_does_not(latency_ms):
    """40 ms is more than a period: only the stated window or the trigger gaps can tell."""
    rng = np.random.default_rng(3)
    kz, tz = stream(rng, 200, 0, 0.2, 0.0)
    kt, tt = stream(rng, 200, latency_ms, 0.6, 0.0)
    window = (0, 30) if latency_ms < 30 else (35, 50)
    ref = reference(tz, P)
    a = assign(tz, tt, P, camera="thermal_left", window_ms=window, ref=ref)
    assert wrong_pairs(kz, kt, ref, a)[0] == 0
    assert "stated latency" in a.segments[0].established_by


def test_ambiguous_without_evidence_fails_naming_what_is_missing():
    rng = np.random.default_rng(4)
    kz, tz = stream(rng, 200, 0, 0.2, 0.0)
    kt, tt = stream(rng, 200, 40, 0.6, 0.0)
    with pytest.raises(TriggerError, match="ambiguous.*missing evidence.*spans more than one trigger period"):
        assign(tz, tt, P, camera="thermal_left", window_ms=(0, 60), where="rec: /thermal/left/image_raw: ")


def test_a_forward_step_on_one_clock_without_imu_is_refused_not_guessed():
    rng = np.random.default_rng(6)
    kz, tz = stream(rng, 300, 0, 0.2, 0.0, step_ms=20)
    kt, tt = stream(rng, 300, 10, 0.6, 0.0)
    with pytest.raises(TriggerError, match="record the IMU"):
        assign(tz, tt, P, camera="thermal_left", window_ms=(0, 30))
