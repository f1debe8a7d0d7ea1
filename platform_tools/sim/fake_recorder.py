"""A stand-in for `ros2 bag record` that writes a real MCAP and misbehaves on request.

    python -m platform_tools.sim.fake_recorder -o BAG [--misbehave MODE] [--rig FILE] TOPIC...

Like rosbag2 it creates the folder BAG, writes BAG/<name>_0.mcap (ROS 2 CDR messages: a small
mono16 image per topic at --rate-hz, by default the rig's trigger rate), splits by size, and on
SIGINT finishes the file (summary and index) and writes metadata.yaml, then exits 0. MODE:

- ``none``            behave
- ``hang-on-sigint``  ignore SIGINT and SIGTERM: only SIGKILL stops it (the file is left without summary)
- ``die-after:S``     exit with status 3 after S seconds, without finishing the file (a crash)
- ``fill-disk``       write --fill-mb-s megabytes per second of payload, as a recorder filling the disk
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np
import yaml
from mcap_ros2.writer import Writer

from platform_tools.rig.conventions import add_rig_options, rig_from_args
from platform_tools.sim import msgs


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="fake_recorder", description=__doc__.split("\n\n")[0])
    p.add_argument("-o", "--output", required=True, type=Path)
    p.add_argument("topics", nargs="+")
    p.add_argument("--rate-hz", type=float, help="frames per second per topic (default: sync.rate_hz, the rig's "
                                                  "trigger rate, from --rig / --set)")
    p.add_argument("--max-bag-size", type=int, default=0, help="split after this many bytes (0: never)")
    p.add_argument("--misbehave", default="none")
    p.add_argument("--fill-mb-s", type=float, default=40.0)
    add_rig_options(p)
    return p.parse_args(argv)


class Bag:
    """The MCAP files of one recording, split by size like rosbag2."""

    def __init__(self, folder: Path, max_size: int):
        self.folder, self.max_size = folder, max_size
        self.index, self.files = -1, []
        self._open_next()

    def _open_next(self) -> None:
        self.index += 1
        path = self.folder / f"{self.folder.name}_{self.index}.mcap"
        self.files.append(path)
        self.f = open(path, "wb")
        self.writer = Writer(self.f, chunk_size=64 * 1024)
        self.schema = self.writer.register_msgdef(*msgs.msgdef("sensor_msgs/Image"))
        self.count = 0

    def write(self, topic: str, t_ns: int, pixels: np.ndarray) -> None:
        self.writer.write_message(topic, self.schema, msgs.image(t_ns, topic.strip("/"), pixels, "mono16"),
                                  log_time=t_ns, publish_time=t_ns, sequence=self.count)
        self.count += 1
        self.f.flush()   # what was written reaches the OS: a kill loses only the open chunk
        if self.max_size and self.f.tell() >= self.max_size:
            self.finish_file()
            self._open_next()

    def finish_file(self) -> None:
        self.writer.finish()
        self.f.close()

    def write_metadata(self, topics: list[str], t0_ns: int, t1_ns: int) -> None:
        meta = {"rosbag2_bagfile_information": {
            "version": 5, "storage_identifier": "mcap",
            "relative_file_paths": [p.name for p in self.files],
            "duration": {"nanoseconds": t1_ns - t0_ns}, "starting_time": {"nanoseconds_since_epoch": t0_ns},
            "message_count": None,
            "topics_with_message_count": [{"topic_metadata": {"name": t, "type": "sensor_msgs/msg/Image",
                                                              "serialization_format": "cdr"}} for t in topics]}}
        (self.folder / "metadata.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    stop = {"requested": False}
    mode, _, param = args.misbehave.partition(":")

    def on_signal(signum, frame):
        if mode == "hang-on-sigint":
            print(f"fake_recorder: ignoring {signal.Signals(signum).name}", file=sys.stderr, flush=True)
            return
        stop["requested"] = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    try:
        args.output.mkdir(parents=False)
    except FileExistsError:
        print(f"fake_recorder: {args.output} exists (ros2 bag record refuses too)", file=sys.stderr)
        return 1
    rate_hz = args.rate_hz or rig_from_args(args).desc.sync.rate_hz
    bag = Bag(args.output, args.max_bag_size)
    print(f"fake_recorder: recording {len(args.topics)} topics to {args.output} (pid {os.getpid()})",
          file=sys.stderr, flush=True)
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 2**14, (24, 32), dtype=np.uint16)
    filler = rng.integers(0, 2**16, (512, 1024), dtype=np.uint16)   # 1 MiB, incompressible
    period = 1.0 / rate_hz
    t0 = time.time_ns()
    start = time.monotonic()
    n = 0
    while not stop["requested"]:
        now = time.monotonic()
        if mode == "die-after" and now - start >= float(param):
            print("fake_recorder: crashing as asked", file=sys.stderr, flush=True)
            os._exit(3)
        t_ns = time.time_ns()
        for topic in args.topics:
            bag.write(topic, t_ns, frame)
        if mode == "fill-disk":
            for _ in range(max(1, int(args.fill_mb_s * period))):
                bag.write("/fill", t_ns, filler)
        n += 1
        time.sleep(max(0.0, start + n * period - time.monotonic()))
    bag.finish_file()
    bag.write_metadata(args.topics, t0, time.time_ns())
    print(f"fake_recorder: stopped cleanly after {n} frames", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
