"""The FFC freeze as evidence of which frame a status row belongs to (platform_tools.dataset.ffcstatus.frame_lag),
on recordings written by rosbags' writer (tests/dataset/rosbags_rig.py): an upstream-style std_msgs/Bool logged before
its image reaches the recorder (so it is stamped with the frame before), and telemetry whose FFC state leads the
frozen image by a frame. The FFC window must still be the freeze the writer made, and no frozen frame exported."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from platform_tools.dataset import ffcstatus
from tests.dataset import rosbags_rig
from tests.dataset.test_dataset_rosbags_pairing import LIMITS, run


def test_frame_lag_lays_the_status_on_the_freeze():
    k = np.array([i for i in range(42) if i not in (3, 24)])      # triggers of the recorded frames (two lost)
    t = (k * 33_333_333).astype(np.int64)
    frozen = (k >= 10) & (k <= 24)                                 # the image repeats from trigger 10 to 24
    index = ffcstatus.trigger_index(t, None, 1e9 / 30)
    assert (index == k - k[0]).all()
    for lag in (-2, -1, 0, 1, 3):
        # the row stamped with the frame of trigger k describes trigger k + lag: it must move `lag` triggers later
        rows = [(int(s), 2 if 10 <= kk + lag <= 24 else 0) for kk, s in zip(k, t)]
        assert ffcstatus.frame_lag(rows, t, frozen, index) == lag
        moved = ffcstatus.shifted(rows, t, lag, index)
        described = [x for x in range(10, 25) if x in k and x - lag in k]      # a lost frame's row is lost with it
        assert sorted(int(s // 33_333_333) for s, v in moved if v == 2) == described
    assert ffcstatus.frame_lag([(int(s), 0) for s in t], t, frozen, index) == 0          # no FFC in the status
    assert ffcstatus.frame_lag([(int(s) + 5, 2) for s in t[8:22]], t, frozen, index) == 0  # own clock: no frame's
    assert ffcstatus.frame_lag([(int(s), 2) for s in t[8:22]], t, np.zeros(len(t), bool), index) == 0  # no freeze


@pytest.mark.slow
@pytest.mark.parametrize("how", ["bool logged before its image", "telemetry one frame early"])
def test_the_ffc_window_is_the_freeze(tmp_path, capsys, rig, how):
    if how.startswith("bool"):
        spec = rosbags_rig.Spec(status="bool", status_log_after_ns=-3_000_000, seed=21)
        lag, source = 1, "status"
    else:
        spec = rosbags_rig.Spec(status=None, telemetry=True, telemetry_ffc_lead=1, seed=22)
        lag, source = 1, "telemetry"
    bag = tmp_path / "bag"
    truth = rosbags_rig.write(bag, spec, rosbags_rig.project_layout(rig))
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    assert code == 0, err
    (w,) = json.loads(out)["ffc"]["thermal_left"]
    assert w["source"] == f"{source} (moved +{lag} trigger onto the FFC freeze)"
    stamp_of = {k: h for h, k in truth["trigger_of"]["thermal_left"].items()}
    ffc = truth["ffc_triggers"]["thermal_left"]
    # the window ends at the first frame after the freeze whose state is known: its row came with the frame `lag`
    # triggers before it, so when that frame was lost on the host, the next one
    after = min(k for k in stamp_of if k > max(ffc) and k - lag in stamp_of)
    assert (w["start_ns"], w["end_ns"]) == (stamp_of[min(ffc)], stamp_of[after])    # the frozen frames, not one early
    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), "--rate", "30", "--ffc-margin", "0", *LIMITS)
    assert code == 0, err
    rows = list(csv.DictReader((ds / "index.csv").open()))
    # with no margin, every complete trigger outside the freeze is exported (check_pairs): the window is not early;
    # it is late by a frame only where the row of the first frame after it was lost with its carrier frame
    of = truth["trigger_of"]
    complete = set(of["zed_left"].values()) & set(of["thermal_left"].values()) & set(of["thermal_right"].values())
    first_after = min(k for k in stamp_of if k > max(ffc))
    flagged = set(ffc) | set(range(first_after, after))           # empty range unless that row was lost
    assert {of["zed_left"][int(r["t_zed_left_ns"])] for r in rows} == complete - flagged
    assert all(of[c][int(r[f"t_{c}_ns"])] == of["zed_left"][int(r["t_zed_left_ns"])]
               for r in rows for c in ("zed_right", "zed_depth", "thermal_left", "thermal_right"))
