"""16 -> 8 bit: bit-identical to the paper's pipeline (FIReStereo utils.py, transcribed below), with
its parameters from the rig description."""
from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from platform_tools.dataset.thermal8 import Params, to_8bit


def paper(image_in: np.ndarray) -> np.ndarray:
    """process_image(image_in, type="firestereo"), as published (numpy semantics kept)."""
    image_in = image_in.copy()
    if np.max(image_in) < 35000:
        image_out = (image_in - np.min(image_in)) / (np.max(image_in) - np.min(image_in)) * 255
    else:
        im_srt = np.sort(image_in.reshape(-1))
        upper_bound = im_srt[round(len(im_srt) * 0.99) - 1]
        lower_bound = im_srt[round(len(im_srt) * 0.01)]
        img = image_in
        img[img < lower_bound] = lower_bound
        img[img > upper_bound] = upper_bound
        image_out = ((img - lower_bound) / (upper_bound - lower_bound)) * 255.0
    clahe = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8)).apply(image_out.astype(np.uint8))
    return cv2.bilateralFilter(clahe, 5, 20, 15)


@pytest.fixture(scope="module")
def params(rig):
    return Params.from_rig(rig)


@pytest.mark.parametrize("base, hot", [(7500, False), (30000, False), (34000, True), (41000, True), (60000, True)])
def test_identical_to_the_paper_on_full_frames(params, base, hot):
    rng = np.random.default_rng(base)
    raw = (base + rng.normal(0, 250, (512, 640)) + np.linspace(0, 1500, 640)).clip(0, 65535).astype(np.uint16)
    if hot:
        raw[200:210, 300:310] = min(base + 20000, 65535)       # a hot spot: the percentile clip matters
    ours, info = to_8bit(raw, params)
    assert np.array_equal(ours, paper(raw))
    assert info["percentile_clip"] == (raw.max() >= 35000)


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(st.integers(16, 80), st.integers(16, 80), st.integers(0, 60000), st.integers(1, 5000), st.integers(0, 2**31))
def test_identical_to_the_paper_on_any_frame(params, h, w, base, spread, seed):
    rng = np.random.default_rng(seed)
    raw = (base + rng.integers(0, spread + 1, (h, w))).clip(0, 65535).astype(np.uint16)
    if raw.max() == raw.min():
        return
    assert np.array_equal(to_8bit(raw, params)[0], paper(raw))


def test_flat_frame_is_black_not_nan(params):
    assert not to_8bit(np.full((64, 80), 9000, np.uint16), params)[0].any()


def test_parameters_come_from_the_rig(rig):
    from platform_tools.rig import load_rig
    raw = (8000 + np.random.default_rng(0).normal(0, 300, (128, 160))).astype(np.uint16)
    other = Params.from_rig(load_rig(overrides=("processing.thermal_8bit.clahe_clip_limit=4.0",)))
    assert not np.array_equal(to_8bit(raw, other)[0], to_8bit(raw, Params.from_rig(rig))[0])
