"""Reading calibration images: which files, and each one as a 2-D array, with one-line errors."""
from __future__ import annotations

import glob
from pathlib import Path

import cv2
import numpy as np

IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".pgm", ".pnm", ".jpg", ".jpeg", ".bmp")
SATURATED_SHARE = 0.5
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_END = b"IEND\xaeB`\x82"


class ImageError(Exception):
    """A file that is not a usable image; ``str()`` names the file and what is wrong."""


def list_images(spec: str | Path) -> list[Path]:
    """Image files of a folder (sorted) or of a glob pattern. Raises ImageError if there are none."""
    text = str(spec)
    p = Path(text)
    if p.is_dir():
        files = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in IMAGE_SUFFIXES)
        if not files:
            others = [q.name for q in p.iterdir() if q.is_file()]
            hint = f" (it holds {len(others)} other files, e.g. {others[0]})" if others else " (it is empty)"
            raise ImageError(f"{p}: no images (.png, .tif, .pgm, ...) in this folder{hint}")
        return files
    if any(ch in text for ch in "*?["):
        files = sorted(Path(q) for q in glob.glob(text) if Path(q).is_file())
        if not files:
            raise ImageError(f"{text}: the pattern matches no files")
        return files
    if p.is_file():
        return [p]
    raise ImageError(f"{text}: no such folder or file")


def load_image(path: str | Path) -> np.ndarray:
    """A single-channel image as uint8 / uint16 / float32; raises ImageError naming the file if it
    cannot be read, is empty, or is saturated (more than half its pixels at the top value)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ImageError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if not data:
        raise ImageError(f"{path}: empty file")
    if data[:8] == PNG_SIGNATURE and not data.rstrip(b"\0").endswith(PNG_END):
        # checked here: libpng would also print its own complaint on stderr
        raise ImageError(f"{path}: corrupt PNG (truncated: no end chunk)")
    img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise ImageError(f"{path}: not a readable image (corrupt or not an image format OpenCV reads)")
    if img.ndim == 3:
        if img.shape[2] == 4:
            img = img[..., :3]
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.shape[2] == 3 else img[..., 0]
    if img.dtype not in (np.uint8, np.uint16):
        img = img.astype(np.float32)
    top = np.iinfo(img.dtype).max if img.dtype.kind == "u" else None
    if top is not None and np.mean(img == top) > SATURATED_SHARE:
        raise ImageError(f"{path}: saturated ({100 * np.mean(img == top):.0f}% of pixels at {top}); "
                         f"lower the gain or let the camera run a flat-field correction")
    if float(img.max()) == float(img.min()):
        raise ImageError(f"{path}: every pixel has the same value ({img.flat[0]}); no picture in it")
    return img
