"""`calibrate thermal-stereo --bag REC`: the thermal stereo pairs of a recording, chosen for calibration and written
as 16-bit PNGs into left/ and right/ of a folder the pair's pipeline then reads, named by their trigger.

A pair is the two Bosons' frames of one trigger pulse, as the export pairs them (platform_tools.dataset.sync.triggers:
the trigger period, each camera's offset of any size, the frame counters, drops, image motion as the last resort),
never the nearest stamps: a Boson stamped more than half a period after the other (USB buffering) would pair every
left frame with the next pulse's right one, which on a moving board is a wrong pose. The triggers are numbered on
the ZED left's clock, so the recording must hold the ZED left images. Then as for one camera (thermal_frames.py):
neither frame in an FFC or frozen; the board found in both among at most MAX_CANDIDATES pairs spread over the
recording; both sharp against the recording's median; the left views together covering the image.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from calibration.commands.thermal_frames import MAX_FRAMES, _frames, ffc_or_frozen, spread, write_png
from platform_tools.rig.conventions import CheckFailed, UserError

#: the rig's streams of the pair, and the folders the pair's pipeline reads (calibration.stereo.pairs)
SIDES = (("thermal_left", "left"), ("thermal_right", "right"))


def trigger_pairs(rec, rig) -> np.ndarray:
    """(n, 2) int: (left frame, right frame) indices into each stream's stamps exposed by the same trigger, in
    trigger order; RecordingError where the trigger assignment is ambiguous (sync.triggers)."""
    from platform_tools.dataset.sync import triggers
    rec.require("zed_left", "thermal_left", "thermal_right",
                why="the thermal frames are paired by the trigger pulse, numbered on the ZED left's clock")
    trig = triggers(rec, rig)
    of = {}
    for cam, _ in SIDES:
        t = trig.cameras[cam].trigger
        of[cam] = {int(k): i for i, k in enumerate(t) if k >= 0}
    common = sorted(set(of["thermal_left"]) & set(of["thermal_right"]))
    return np.array([(of["thermal_left"][k], of["thermal_right"][k]) for k in common], int).reshape(-1, 2)


def _both(rec, pairs: np.ndarray):
    """(j, left image, right image, left stamp) of each pair ``pairs[j]``, decoded."""
    got = {}
    for side, (cam, _) in enumerate(SIDES):
        for k, stamp, img in _frames(rec, cam, np.unique(pairs[:, side])):
            got[(side, k)] = (img, stamp)
    for j, (a, b) in enumerate(pairs):
        if (0, a) in got and (1, b) in got:
            yield j, got[(0, a)][0], got[(1, b)][0], got[(0, a)][1]


def select_pairs(bag: Path, board, target: str, rig, stage: Path, max_pairs: int = MAX_FRAMES) -> dict:
    """Write the chosen pairs into ``stage``/left and ``stage``/right as <trigger>.png; returns what was chosen and
    why the others were left out."""
    from calibration.detect.targets import detect_target
    from calibration.frames import board_sharpness, coverage_greedy, sharp_mask
    from platform_tools.dataset.recording import RecordingError, open_recording
    try:
        rec = open_recording(Path(bag), rig)
        pairs = trigger_pairs(rec, rig)
    except RecordingError as exc:
        raise UserError(f"--bag {exc}") from None
    masks = [ffc_or_frozen(rec, cam) for cam, _ in SIDES]
    ok = ~masks[0][0][pairs[:, 0]] & ~masks[1][0][pairs[:, 1]] if len(pairs) else np.zeros(0, bool)
    cand = spread(pairs[ok])
    found, corners, sharp = [], [], []
    for j, left, right, _ in _both(rec, cand):
        dl, dr = detect_target(left, board, target), detect_target(right, board, target)
        if dl.detected and dr.detected:
            found.append(j)
            corners.append(dl.corners)
            sharp.append(min(board_sharpness(left, dl.corners), board_sharpness(right, dr.corners)))
    keep = sharp_mask(np.array(sharp))
    usable = [i for i in range(len(found)) if keep[i]]
    size = masks[0][2]
    picked = coverage_greedy([corners[i] for i in usable], size, max_frames=max_pairs) if usable else []
    chosen = cand[[found[usable[i]] for i in picked]] if picked else np.zeros((0, 2), int)
    if not len(chosen):
        raise CheckFailed(f"--bag {bag}: no {board[0]}x{board[1]} {target} seen by both thermal cameras in the "
                          f"{len(cand)} pairs outside FFC looked at; check --board / --target")
    trig_of = {}
    for j, left, right, _ in _both(rec, chosen):
        name = f"{j:06d}.png"
        for img, (_, folder) in ((left, SIDES[0]), (right, SIDES[1])):
            write_png(stage / folder / name, img, f"--bag {bag}: pair {name}, the {folder} frame")
        trig_of[name] = [int(rec.streams[c].stamp_ns[k]) for (c, _), k in zip(SIDES, chosen[j])]
    return {"bag": str(bag), "paired_by": "trigger", "pairs": int(len(pairs)),
            "ffc_or_frozen": int(len(pairs) - ok.sum()), "looked_at": int(len(cand)), "with_board_in_both": len(found),
            "blurred": int(len(found) - len(usable)), "chosen": len(chosen),
            "chosen_stamps_ns": {n: v for n, v in sorted(trig_of.items())}}
