"""A recording copied message for message by the rosbags library's writer: the export bench's second source.

The bag of RECORDING (a folder with ``bag/`` and the files beside it, as ``platform_tools simulate-rig`` writes
it) is read with rosbags' reader and written again with rosbags' writer (MCAP storage): the same raw CDR bytes, log
times, topics, types and offered QoS, in another writer's chunks (about 1 MiB each, closed as rosbags closes them)
and records. ``--zstd``: the chunks zstd-compressed (rosbags' storage compression), else uncompressed, as rosbags
writes them by default. The files beside the bag (truth.json) are copied.

    .venv/bin/python bench/rosbags_copy.py /tmp/rec/full60 /tmp/rec/rb60 [--zstd]
    .venv/bin/python bench/bench_dataset.py --export /tmp/rec/rb60 [--cold]

Exit codes: 0 written; 2 bad input (no bag in RECORDING, OUT exists); OUT is written into a temporary folder beside
it and renamed when complete.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path


def copy(src: Path, dst: Path, zstd: bool = False) -> int:
    """Write ``dst`` (a recording folder) from ``src``'s bag with rosbags' writer; the number of messages."""
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
    tmp = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", dir=dst.parent))
    try:
        for f in src.iterdir():
            if f.is_file():
                shutil.copy(f, tmp / f.name)
        n = 0
        with Reader(src / "bag") as reader:
            writer = Writer(tmp / "bag", version=8, storage_plugin=StoragePlugin.MCAP)
            if zstd:
                writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
            with writer:
                conns = {c.id: writer.add_connection(
                    c.topic, c.msgtype, msgdef=c.msgdef.data,
                    rihs01=c.digest or "RIHS01_" + "0" * 64,      # a bag without type hashes (rosbag2 humble's)
                    serialization_format=c.ext.serialization_format,
                    offered_qos_profiles=c.ext.offered_qos_profiles) for c in reader.connections}
                for c, log_time, raw in reader.messages():
                    writer.write(conns[c.id], log_time, raw)
                    n += 1
        tmp.rename(dst)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__.split("Exit codes:")[1].strip(),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("recording", type=Path, help="a recording folder holding bag/")
    ap.add_argument("out", type=Path, help="the copy's folder (must not exist)")
    ap.add_argument("--zstd", action="store_true", help="zstd-compressed chunks (default: uncompressed)")
    args = ap.parse_args(argv)
    if not (args.recording / "bag" / "metadata.yaml").is_file():
        print(f"rosbags_copy: {args.recording}: no bag/metadata.yaml", file=sys.stderr)
        return 2
    if args.out.exists():
        print(f"rosbags_copy: {args.out}: exists; not overwritten", file=sys.stderr)
        return 2
    n = copy(args.recording, args.out, args.zstd)
    print(f"{args.out}: {n} messages ({'zstd' if args.zstd else 'uncompressed'} chunks, rosbags' writer)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
