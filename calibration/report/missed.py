"""Why an image gave no board, in the report's words, from what the detector said about it.

The detector (calibration/detect) gives a reason and how many corner candidates survived its ring
test; an unreadable or saturated image never reaches it (calibration/detect/images.py). Each image
without a board gets one of these causes and what to do about it:

- ``over-exposed``: more than half the pixels at the top value (calibration/detect/images.py);
- ``blank``: every pixel the same value;
- ``no candidates``: no X-shaped corner anywhere (a flat or featureless view);
- ``no grid``: corner candidates, but none that link into a grid of corners: no board in view, or a
  board too faint, too blurred or too small for its corners to link (the detector reports only the
  candidates' count, so these cannot be told apart here: measured, a Gaussian blur of sigma 8 px on an
  8-bit board image and pure noise give the same "no grid of corners found", with 137 and 288
  candidates);
- ``grid too small``: a grid, but of one row or column only;
- ``partial and unlabelable``: a grid, but a partial one whose place on the board cannot be proven
  (no board edge in view), or one that ends before the --board size (a wrong --board).
"""
from __future__ import annotations

from dataclasses import dataclass

ACTIONS = {
    "over-exposed": "lower the gain or the board's temperature, or run a flat-field correction",
    "blank": "check the camera and the file",
    "no candidates": "put the board in view, warmer or cooler than its background",
    "no grid": "put the board in view, in focus, with more contrast to its background, or closer",
    "grid too small": "bring the board closer or make more of it visible",
    "partial and unlabelable": "keep at least one board edge in view (or check --board: inner corners across x down)",
    "no reason given": "",
}


@dataclass(frozen=True)
class Missed:
    name: str
    cause: str           # one of ACTIONS
    detail: str          # what the detector (or the image check) said

    def line(self) -> str:
        what = ACTIONS.get(self.cause, "")
        return f"{self.name}: {self.cause} ({self.detail})" + (f"; {what}" if what else "")

    def to_dict(self) -> dict:
        return dict(name=self.name, cause=self.cause, detail=self.detail, action=ACTIONS.get(self.cause, ""))


def classify(name: str, reason: str, candidates: int = 0) -> Missed:
    """The cause of an image without a board from the detector's ``reason`` (or the image check's error
    text) and its ``candidates`` count."""
    r = (reason or "").strip()
    low = r.lower()
    if "saturated" in low:
        return Missed(name, "over-exposed", r)
    if "same value" in low or "image is flat" in low:
        return Missed(name, "blank", r)
    if "partial board" in low or "board ends after" in low or "cannot tell" in low:
        return Missed(name, "partial and unlabelable", r)
    if "one row" in low or "too few" in low:
        return Missed(name, "grid too small", r)
    if "no grid" in low:
        if candidates <= 0:
            return Missed(name, "no candidates", "no corner candidates")
        return Missed(name, "no grid", f"{candidates} corner candidates, none linking into a grid")
    if not r:
        return Missed(name, "no reason given", "the detector gave no reason")
    return Missed(name, "no reason given", r)


def counts(missed: list[Missed]) -> dict[str, int]:
    out: dict[str, int] = {}
    for m in missed:
        out[m.cause] = out.get(m.cause, 0) + 1
    return out
