"""The check after a recording stops, old and new, on the same multi-GB MCAP.

old:      mcapcheck.check (every message record read through mcap's reader, counted against the summary);
serial:   mcapverify.check_crcs(workers=1) (the summary and its CRC, the data section CRC when the writer
          computed one, each chunk it indexes read once and its CRC compared; no message parsed), in
          this process: the previous session's check_crcs plus the summary CRC;
parallel: the same with one worker process per CPU (data-CRC pieces combined, runs of chunks). Both on a file written by the mcap library (another writer than either check's
reader path) with the rig's thermal frames (640x514 mono16, a smooth scene plus sensor noise, so zstd
compresses it as it would a real one) at 2 x 30 Hz, in rosbag2's chunk size (about 1 MiB chunks before
compression). The file is read once before timing (page cache) so both measure the check, not the disk.

Run: .venv/bin/python bench/bench_mcapcheck.py [--gb 2] [--data-crc] [--keep FILE] [--json]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from firmware.device import mcapcheck, mcapverify  # noqa: E402

WIDTH, HEIGHT = 640, 514
CHUNK_BYTES = 1024 * 1024


def thermal_frames(n: int, seed: int = 0) -> list[bytes]:
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    base = 22000 + 800 * np.sin(x / 90.0) + 600 * np.cos(y / 70.0)
    return [(base + rng.normal(0, 25, base.shape)).astype("<u2").tobytes() for _ in range(n)]


def write(path: Path, gb: float, data_crc: bool = False) -> int:
    from mcap.writer import CompressionType, Writer
    frames = thermal_frames(8)
    n_msgs = int(gb * 1e9 / len(frames[0]))
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=CHUNK_BYTES, enable_data_crcs=data_crc)
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
    ap.add_argument("--keep", type=Path, help="write the MCAP here and keep it; an existing one is reused")
    ap.add_argument("--data-crc", action="store_true",
                    help="write the DataEnd data_section_crc (rosbag2's presets do not)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or Path(tmp) / "bench.mcap"
        t0 = time.perf_counter()
        if args.keep and args.keep.exists():
            from mcap.reader import make_reader
            with open(path, "rb") as f:
                n = make_reader(f).get_summary().statistics.message_count
        else:
            n = write(path, args.gb, args.data_crc)
        t_write = time.perf_counter() - t0
        size = path.stat().st_size
        with open(path, "rb") as f:     # warm the page cache for all
            while f.read(1 << 24):
                pass
        workers = os.cpu_count() or 1
        t_old, old = timed(mcapcheck.check, path)
        t_serial, serial = timed(lambda p: mcapverify.check_crcs(p, workers=1), path)
        t_par, par = timed(lambda p: mcapverify.check_crcs(p, workers=workers, min_parallel_bytes=0), path)
        t_data = None
        if "data crc" in par.verified:     # the data CRC alone, no decompression, in parallel
            t_data, data = timed(lambda p: mcapverify.check_crcs(p, workers, min_parallel_bytes=0, chunks=False), path)
            assert data.ok and data.verified == ("summary", "data crc"), data
    assert old.ok and serial.ok and par.ok and old.messages == serial.messages == par.messages == n, (old, serial, par)
    assert serial.verified == par.verified, (serial, par)
    res = {"messages": n, "payload_gb": round(args.gb, 2), "file_gb": round(size / 1e9, 3), "cpus": workers,
           "verified": list(par.verified), "write_s": round(t_write, 2), "old_check_s": round(t_old, 2),
           "serial_crc_s": round(t_serial, 2), "parallel_crc_s": round(t_par, 2),
           "old_over_serial": round(t_old / t_serial, 1), "old_over_parallel": round(t_old / t_par, 1),
           "serial_over_parallel": round(t_serial / t_par, 2),
           "data_crc_only_s": None if t_data is None else round(t_data, 2),
           "serial_file_gb_per_s_per_core": round(size / 1e9 / t_serial, 2)}
    if args.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k:26s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
