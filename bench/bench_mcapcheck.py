"""The check after a recording stops, old and new, on the same multi-GB MCAP.

old: mcapcheck.check (every message record read through mcap's reader, counted against the summary);
new: mcapcheck.check_crcs (the summary, then each chunk it indexes read once and its CRC compared; no
message record parsed). Both on a file written by the mcap library (another writer than either check's
reader path) with the rig's thermal frames (640x514 mono16, a smooth scene plus sensor noise, so zstd
compresses it as it would a real one) at 2 x 30 Hz, in rosbag2's chunk size (about 1 MiB chunks before
compression). The file is read once before timing (page cache) so both measure the check, not the disk.

Run: .venv/bin/python bench/bench_mcapcheck.py [--gb 2] [--keep FILE] [--json]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from firmware.device import mcapcheck  # noqa: E402

WIDTH, HEIGHT = 640, 514
CHUNK_BYTES = 1024 * 1024


def thermal_frames(n: int, seed: int = 0) -> list[bytes]:
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    base = 22000 + 800 * np.sin(x / 90.0) + 600 * np.cos(y / 70.0)
    return [(base + rng.normal(0, 25, base.shape)).astype("<u2").tobytes() for _ in range(n)]


def write(path: Path, gb: float) -> int:
    from mcap.writer import CompressionType, Writer
    frames = thermal_frames(8)
    n_msgs = int(gb * 1e9 / len(frames[0]))
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=CHUNK_BYTES)
        w.start(profile="ros2", library="bench_mcapcheck")
        schema = w.register_schema("sensor_msgs/msg/Image", "ros2msg", b"")
        chans = [w.register_channel(f"/thermal/{s}/image_raw", "cdr", schema) for s in ("left", "right")]
        for i in range(n_msgs):
            t = 1_700_000_000_000_000_000 + (i // 2) * 33_333_333
            w.add_message(chans[i % 2], t, frames[i % len(frames)], t, i)
        w.finish()
    return n_msgs


def timed(fn, path):
    t0 = time.perf_counter()
    status = fn(path)
    return time.perf_counter() - t0, status


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gb", type=float, default=2.0, help="uncompressed payload to write (default 2)")
    ap.add_argument("--keep", type=Path, help="write the MCAP here and keep it")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or Path(tmp) / "bench.mcap"
        t0 = time.perf_counter()
        n = write(path, args.gb)
        t_write = time.perf_counter() - t0
        size = path.stat().st_size
        with open(path, "rb") as f:     # warm the page cache for both
            while f.read(1 << 24):
                pass
        t_old, old = timed(mcapcheck.check, path)
        t_new, new = timed(mcapcheck.check_crcs, path)
    assert old.ok and new.ok and old.messages == new.messages == n, (old, new, n)
    res = {"messages": n, "payload_gb": round(args.gb, 2), "file_gb": round(size / 1e9, 3),
           "write_s": round(t_write, 2), "old_check_s": round(t_old, 2), "new_check_s": round(t_new, 2),
           "speedup": round(t_old / t_new, 1),
           "new_gb_per_s_of_payload": round(args.gb / t_new, 2)}
    if args.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k:26s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
