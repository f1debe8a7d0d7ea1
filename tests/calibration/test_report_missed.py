"""Images without a board say why (calibration/report/missed.py), from what the real detector and the
image check say about real files, and 8-bit input is flagged in the summary and the report."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from calibration.report.input_depth import note
from calibration.report.missed import ACTIONS, classify, counts


def test_every_cause_has_an_action_and_unknown_reasons_are_kept_verbatim():
    m = classify("a.png", "something new the detector says")
    assert m.cause == "no reason given" and "something new" in m.line()
    assert all(c in ACTIONS for c in ("over-exposed", "blank", "no candidates", "no grid", "grid too small",
                                      "partial and unlabelable"))
    assert counts([m, m]) == {"no reason given": 2}


def test_an_8bit_input_note_says_accuracy_is_reduced_and_16bit_gets_none():
    assert note(16) is None and note(None) is None
    t = note(8).text
    assert "8-bit" in t and "reduced" in t and "16-bit" in t
    # the figures it quotes are the module's measured ones, and say how much worse 8-bit was
    from calibration.report import input_depth as d
    assert f"{d.CORNER_RMS_8_PX:.3f} px" in t and f"{d.CORNER_RMS_16_PX:.3f} px" in t
    assert d.CORNER_RMS_8_PX > d.CORNER_RMS_16_PX and d.MODEL_CENTRAL_8_PX > d.MODEL_CENTRAL_16_PX


@pytest.mark.slow
def test_calibrate_detect_stage_names_the_cause_of_each_image_without_a_board(tmp_path):
    """One rendered board image (8-bit AGC), and beside it: pure noise, a flat frame, a saturated frame,
    the board blurred away, and the same board asked for as 9x9 (a wrong --board)."""
    from calibration.synth import render_dataset
    from calibration.thermal.pipeline import detect
    src = tmp_path / "src"
    render_dataset(src, n=1, difficulty="easy", board=(8, 8), square=0.04, seed=2, output="agc8",
                   show_progress=False)
    img = cv2.imread(str(src / "000.png"), cv2.IMREAD_UNCHANGED)
    d = tmp_path / "imgs"
    d.mkdir()
    cv2.imwrite(str(d / "board.png"), img)
    rng = np.random.default_rng(0)
    cv2.imwrite(str(d / "noise.png"), rng.normal(128, 3, img.shape).clip(0, 255).astype(np.uint8))
    cv2.imwrite(str(d / "flat.png"), np.full(img.shape, 90, np.uint8))
    sat = img.copy()
    sat[:, : img.shape[1] * 3 // 4] = 255
    cv2.imwrite(str(d / "saturated.png"), sat)
    cv2.imwrite(str(d / "blurred.png"), cv2.GaussianBlur(img, (0, 0), 8))
    obs, _ = detect(str(d), (8, 8), 0.04)
    why = {m.name: m.cause for m in obs.missed_why}
    assert obs.names == ["board.png"] and obs.bit_depth == 8
    assert why == {"noise.png": "no grid", "flat.png": "blank", "saturated.png": "over-exposed",
                   "blurred.png": "no grid"}, why
    # a wrong --board on a visible board: the board ends early
    from calibration.detect.detector import detect_corners
    m = classify("board.png", detect_corners(img, (9, 9)).reason)
    assert m.cause == "partial and unlabelable" and "--board" in m.line()
