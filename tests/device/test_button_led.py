"""The button's debounce and press classification, and the LED's blink codes, with exact timings."""
from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from firmware.device import led
from firmware.device.button import Button, Press

DT = 0.005   # 200 Hz sampling, as the service loop (10 ms) or faster


def feed(button: Button, levels_by_time: list[tuple[float, int]], until: float) -> list[tuple[float, Press]]:
    """Sample a piecewise-constant raw signal [(t_from, level), ...] every DT until `until`."""
    out, i, t = [], 0, 0.0
    while t <= until:
        while i + 1 < len(levels_by_time) and levels_by_time[i + 1][0] <= t:
            i += 1
        out += [(t, p) for p in button.sample(t, levels_by_time[i][1])]
        t = round(t + DT, 9)
    return out


def test_a_clean_press_is_one_short_press_reported_on_release():
    events = feed(Button(0.2, 3.0), [(0, 1), (1.0, 0), (1.5, 1)], 2.5)
    assert [p for _, p in events] == [Press.SHORT]
    assert 1.7 <= events[0][0] <= 1.75          # released at 1.5, stable for 0.2 s


def test_a_bouncing_press_is_one_press():
    bounce = [(1.0, 0), (1.01, 1), (1.02, 0), (1.035, 1), (1.05, 0)]          # contact chatter on press
    release = [(1.6, 1), (1.61, 0), (1.625, 1)]                             # and on release
    events = feed(Button(0.2, 3.0), [(0, 1)] + bounce + release, 3.0)
    assert [p for _, p in events] == [Press.SHORT]


def test_a_glitch_shorter_than_the_bounce_time_is_ignored():
    b = Button(0.2, 3.0)
    assert feed(b, [(0, 1), (1.0, 0), (1.15, 1)], 3.0) == []
    assert b.bounces >= 1


def test_a_long_press_is_reported_while_held_and_not_again_on_release():
    events = feed(Button(0.2, 3.0), [(0, 1), (1.0, 0), (5.0, 1)], 6.0)
    assert [p for _, p in events] == [Press.LONG]
    assert 4.0 <= events[0][0] <= 4.3         # held 3 s from the (debounced) press


def test_active_high_buttons():
    events = feed(Button(0.05, 3.0, active_low=False), [(0, 0), (1.0, 1), (1.3, 0)], 2.0)
    assert [p for _, p in events] == [Press.SHORT]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.25, 1.5), st.lists(st.floats(0.001, 0.04), max_size=5)),
                min_size=1, max_size=4))
def test_chatter_never_adds_or_loses_a_press(presses):
    """Each press: chatter (each bounce < 40 ms, 200 ms debounce), a hold, chatter again, a pause."""
    signal, t = [(0.0, 1)], 0.5
    for hold, chatter in presses:
        for d in chatter:
            signal += [(t, 0), (t + d / 2, 1)]
            t += d
        signal.append((t, 0))
        t += hold
        for d in chatter:
            signal += [(t, 1), (t + d / 2, 0)]
            t += d
        signal.append((t, 1))
        t += 0.6
    events = feed(Button(0.2, 3.0), signal, t + 0.5)
    assert [p for _, p in events] == [Press.SHORT] * len(presses)


def test_error_blink_codes_count():
    for code in led.ErrorCode:
        period = int(code) * (led.BLINK_ON_S + led.BLINK_OFF_S) + led.CODE_PAUSE_S
        levels = [led.level_at("error", i * 0.01, int(code)) for i in range(int(period / 0.01))]
        assert led.count_blinks([0] + levels) == int(code)


def test_state_patterns_differ():
    ts = [i * 0.01 for i in range(400)]
    assert all(led.level_at("recording", t) == 1 for t in ts)
    assert led.count_blinks([led.level_at("stopping", t) for t in ts]) >= 15
    assert led.count_blinks([led.level_at("idle", t) for t in ts]) <= 2
