"""`calibrate thermal --bag REC --topic T`: the frames of one thermal topic of a recording, chosen for
calibration (calibration/frames/select.py: sharp against the recording's own median, not during an
FFC, together covering the image), written as 16-bit PNGs into a folder the pipeline then reads.

Reading the bag is platform_tools.dataset's (open_recording, iter_frames, ffc_periods: the status topic
when the recording has one, frozen frames otherwise); frozen frames are also judged here on the
decoded pixels. Three passes over the topic, each decoding only what it needs: frozen frames; the
board in at most MAX_CANDIDATES of the FFC-free frames (evenly spread over the recording) and its
sharpness inside the board's hull, against the median of those; the chosen ones, written out.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from platform_tools.rig.conventions import CheckFailed, UserError

MAX_CANDIDATES = 300     # frames the board is looked for in
MAX_FRAMES = 40          # frames calibrated from


def _stream_of(rec, topic: str) -> str:
    names = [s for s, st in rec.streams.items() if st.topic == topic and s.startswith("thermal")]
    if not names or not rec.has(names[0]):
        have = sorted(st.topic for s, st in rec.streams.items() if s.startswith("thermal") and rec.has(s))
        raise UserError(f"--topic {topic}: no thermal images on that topic in {rec.path} "
                        f"(thermal image topics there: {', '.join(have) or 'none'})")
    return names[0]


def _frames(rec, stream: str, index: np.ndarray):
    """(k, stamp, image) of the frames ``index`` of ``stream``, decoded."""
    from platform_tools.dataset.decode import iter_frames
    st = rec.streams[stream]
    for fi, f in enumerate(rec.files):
        sel = [int(k) for k in index if int(st.file_index[k]) == fi]
        if not sel:
            continue
        wanted = {(st.topic, int(st.stamp_ns[k])): k for k in sel}
        for k, stamp, img in iter_frames([str(f)], wanted, st.log_ns[sel]):
            if img.ndim == 3:
                img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
            yield k, stamp, img


def spread(cand: np.ndarray, most: int = MAX_CANDIDATES) -> np.ndarray:
    """At most ``most`` of the candidates ``cand`` (frames, or pairs of frames), evenly spread over them."""
    if len(cand) > most:
        cand = cand[np.linspace(0, len(cand) - 1, most).round().astype(int)]
    return cand


def write_png(path: Path, img: np.ndarray, what: str) -> None:
    """``img`` as the PNG file ``path``; UserError naming ``what`` (the frame) when OpenCV cannot encode it."""
    ok, png = cv2.imencode(".png", img)
    if not ok:
        raise UserError(f"{what}: cannot be written as PNG ({img.dtype}, {img.shape})")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(png.tobytes())


def ffc_or_frozen(rec, stream: str) -> tuple[np.ndarray, list, tuple[int, int] | None]:
    """(bool (n,): each frame of ``stream`` in an FFC (the recording's status or telemetry, ffc_periods, with
    calibration.frames' margin) or frozen on its decoded pixels, the FFC spans, the image (width, height))."""
    from calibration.frames import ffc_mask, frozen_mask
    from platform_tools.dataset.sync import ffc_periods
    st = rec.streams[stream]
    n = len(st.stamp_ns)
    frozen, size = np.zeros(n, bool), None
    prev = None
    for k, _, img in _frames(rec, stream, np.argsort(st.log_ns, kind="stable")):
        frozen[k] = prev is not None and bool(frozen_mask([prev, img])[1])
        prev, size = img, (img.shape[1], img.shape[0])
    period = float(np.median(np.diff(np.sort(st.stamp_ns)))) if n > 1 else 1e9 / 30
    spans = ffc_periods(rec, stream, period)
    return ffc_mask(st.stamp_ns, [(p["start_ns"], p["end_ns"]) for p in spans]) | frozen, spans, size


def select_frames(bag: Path, topic: str, board, target: str, rig, stage: Path,
                  max_frames: int = MAX_FRAMES) -> dict:
    """Write the chosen frames of ``topic`` into ``stage`` as <stamp_ns>.png; returns what was chosen and
    why the others were left out (frames.json)."""
    from calibration.detect.targets import detect_target
    from calibration.frames import board_sharpness, coverage_greedy, sharp_mask
    from platform_tools.dataset.recording import RecordingError, open_recording
    try:
        rec = open_recording(Path(bag), rig)
    except RecordingError as exc:
        raise UserError(f"--bag {exc}") from None
    stream = _stream_of(rec, topic)
    st = rec.streams[stream]
    n = len(st.stamp_ns)
    in_ffc, spans, size = ffc_or_frozen(rec, stream)
    cand = spread(np.flatnonzero(~in_ffc))
    corners, idx, sharp = [], [], []
    for k, _, img in _frames(rec, stream, cand):
        det = detect_target(img, board, target)
        if det.detected:
            idx.append(k)
            corners.append(det.corners)
            sharp.append(board_sharpness(img, det.corners))
    keep = sharp_mask(np.array(sharp))
    usable = [j for j in range(len(idx)) if keep[j]]
    chosen = [idx[usable[j]] for j in coverage_greedy([corners[j] for j in usable], size, max_frames=max_frames)]
    if not chosen:
        raise CheckFailed(f"--bag {bag}: no {board[0]}x{board[1]} {target} found in the {len(cand)} frames of "
                          f"{topic} outside FFC looked at; check --board / --target")
    for k, stamp, img in _frames(rec, stream, np.array(chosen)):
        write_png(stage / f"{stamp:019d}.png", img, f"--bag {bag}: {topic} frame {stamp}")
    return {"bag": str(bag), "topic": topic, "frames": n, "ffc_spans": spans,
            "ffc_or_frozen": int(in_ffc.sum()), "looked_at": int(len(cand)), "with_board": len(idx),
            "blurred": int(len(idx) - len(usable)), "board_sharpness_median": float(np.median(sharp)) if sharp else 0.0,
            "chosen_stamps_ns": sorted(int(st.stamp_ns[k]) for k in chosen)}
