"""`platform_tools export RECORDING... --out DIR`: recordings to a registered RGB-thermal dataset."""
from __future__ import annotations

import argparse
import signal
from pathlib import Path

from platform_tools.rig.conventions import (EXIT_INTERRUPTED, UserError, add_output_options, add_rig_options, error,
                                            print_json, rig_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="recordings to a dataset: paired, FFC-filtered, 8-bit thermal, registered RGB",
                       description="Pair the four cameras (within processing.pair_tolerance_ms after their constant "
                                   "offsets), drop thermal frames during FFC and processing.ffc_margin_frames on each "
                                   "side, sample at --rate, convert thermal to 8-bit as the paper (min-max with "
                                   "percentile clip, CLAHE, bilateral; processing.thermal_8bit) keeping the 16-bit "
                                   "original, register the ZED left RGB into each thermal view from the ZED "
                                   "depth (--depth; z-buffer, bilinear splatting, validity mask), and write PNGs with "
                                   "index.csv / index.parquet and a dataset card (README.md). Run the same command "
                                   "again to resume an interrupted export (Ctrl-C or SIGTERM stops every worker and "
                                   "keeps the finished chunks; workers end if this process is killed); a folder "
                                   "holding a different export is refused.",
                       epilog="Workers (--workers N > 1): forked from this process on Linux (the default there; "
                              "each loads its kernels after indexing), spawned elsewhere or when this process runs "
                              "other threads; "
                              "the environment variable PLATFORM_TOOLS_EXPORT_WORKERS=fork|spawn chooses "
                              "(docs/dataset.md \"Speed and clean stops\"). "
                              "Exit codes: 0 done, 2 bad input (one line naming the file, topic or option; nothing "
                              "written), 130 interrupted (resumable).")
    p.add_argument("recordings", metavar="RECORDING", nargs="+", type=Path,
                   help="rosbag2 folders, folders holding one (simulate-rig's DIR), or .mcap files")
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="the dataset folder (created; resumed)")
    p.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="samples per second (default processing.pair_rate_hz)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes (default: the CPUs this process may use; 1: everything in this "
                        "process); forked on Linux, see PLATFORM_TOOLS_EXPORT_WORKERS below")
    p.add_argument("--engine", choices=("pool", "dask"), default="pool",
                   help="pool: a process pool on this machine (default); dask: dask.distributed, a local "
                        "cluster of --workers processes or --scheduler's")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="with --engine dask: a running scheduler, e.g. tcp://10.0.0.1:8786 (workers must see "
                        "the recordings and --out at the same paths)")
    p.add_argument("--calibration", metavar="DIR", type=Path,
                   help="folder of mrcal .cameramodel files as `calibrate nominal` names them (default: the "
                        "recording's camera_info topics when it has them, else the rig's nominal models)")
    p.add_argument("--topics", metavar="FILE", type=Path,
                   help="a YAML topic map (stream: /topic) for a recording in neither this rig's layout nor the "
                        "TartanRGBT stack's (both detected without it); see docs/dataset.md")
    p.add_argument("--depth", default="auto", metavar="recorded|stereo|MODULE:FUNCTION",
                   help="where the ZED left depth comes from: recorded (the depth topic), stereo (OpenCV SGBM on "
                        "the rectified left/right pair, CPU), or a plug-in function(left, right, calib) -> "
                        "(depth_m, confidence) for learned stereo (docs/dataset.md); default: recorded when the "
                        "recording has a depth topic, else stereo")
    p.add_argument("--tolerance-ms", type=float, default=None,
                   help="pairing tolerance after the offsets (default processing.pair_tolerance_ms)")
    p.add_argument("--ffc-margin", type=int, default=None, metavar="FRAMES",
                   help="frames dropped on each side of an FFC (default processing.ffc_margin_frames)")
    p.add_argument("--keep-ffc", action="store_true", help="keep FFC frames (flagged in the index)")
    p.add_argument("--chunk-size", type=int, default=8, metavar="N",
                   help="samples per unit of work (default 8); a recording's last chunks are smaller (N/2, N/2, "
                        "N/4, N/4, ... 1, 1) so that the workers end together")
    p.add_argument("--paper", action="store_true",
                   help="the dataset as the paper releases it: 1 Hz pairs, per thermal camera its 8-bit image, the "
                        "RGB registered into it and the validity mask (no raw16, depth or ZED images)")
    p.add_argument("--png-level", type=int, default=None, metavar="0-9",
                   help="zlib level of the PNGs through OpenCV's libpng (default processing.png_compression_level; "
                        "null there: the export's own writer, ISA-L deflate level 1 with the UP filter, about 3x "
                        "faster than libpng's level 1, the same pixels); 6 is several times slower and smaller "
                        "(docs/dataset.md)")
    p.add_argument("--zed-images", choices=_zed_images(), default=None,
                   help="the ZED images: as_recorded writes a compressed topic's JPEG as the recording holds it, byte "
                        "for byte (smaller, faster, no second encoding), a raw topic as PNG; png decodes and writes "
                        "every one as PNG (default processing.zed_images)")
    p.add_argument("--recover", action="store_true",
                   help="salvage a truncated MCAP into NAME.recovered.mcap beside it (the original is kept)")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_export)


def _zed_images() -> tuple[str, ...]:
    """The values of processing.zed_images, as the rig schema declares them (chunk.ZED_IMAGES is tested equal)."""
    import typing

    from platform_tools.rig.schema import Processing
    return typing.get_args(typing.get_type_hints(Processing)["zed_images"])



#: (option, attribute, default) of the options that go into the dataset card's command line when not default
_OPTIONS = (("--rate", "rate", None), ("--workers", "workers", None), ("--engine", "engine", "pool"),
            ("--scheduler", "scheduler", None), ("--calibration", "calibration", None), ("--topics", "topics", None),
            ("--depth", "depth", "auto"), ("--tolerance-ms", "tolerance_ms", None), ("--ffc-margin", "ffc_margin", None),
            ("--keep-ffc", "keep_ffc", False), ("--chunk-size", "chunk_size", 8), ("--paper", "paper", False),
            ("--png-level", "png_level", None), ("--zed-images", "zed_images", None), ("--recover", "recover", False),
            ("--rig", "rig", None))


def command_line(args: argparse.Namespace) -> list[str]:
    """The command as it was given (its non-default options, in a fixed order), however it was invoked."""
    cmd = ["platform_tools", "export", *map(str, args.recordings), "--out", str(args.out)]
    for opt, attr, default in _OPTIONS:
        v = getattr(args, attr, default)
        if v == default:
            continue
        cmd += [opt] if v is True else [opt, f"{v:g}" if isinstance(v, float) else str(v)]
    for o in args.overrides:
        cmd += ["--set", o]
    return cmd


def _terminated(signum, frame):
    """SIGTERM (docker stop, a scheduler's kill) stops the export as Ctrl-C does: workers stopped, resumable."""
    raise KeyboardInterrupt


def cmd_export(args: argparse.Namespace) -> int:
    from ..dataset.engines import usable_cpus
    from ..dataset.export import PAPER_OUTPUTS, PAPER_RATE_HZ, ExportError, Params, export
    from ..dataset.layout import LayoutError, load_topic_map
    from ..dataset.stereo import BUILT_IN, StereoError, load_plugin
    if args.rate is not None and not 0 < args.rate <= 1000:
        raise UserError(f"--rate {args.rate:g}: expected more than 0 and at most 1000 Hz")
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers {args.workers}: expected 1 or more")
    if args.chunk_size < 1:
        raise UserError(f"--chunk-size {args.chunk_size}: expected 1 or more")
    if args.tolerance_ms is not None and args.tolerance_ms <= 0:
        raise UserError(f"--tolerance-ms {args.tolerance_ms:g}: expected more than 0")
    if args.ffc_margin is not None and args.ffc_margin < 0:
        raise UserError(f"--ffc-margin {args.ffc_margin}: expected 0 or more")
    if args.depth not in BUILT_IN:
        try:
            load_plugin(args.depth)
        except StereoError as exc:
            raise UserError(str(exc)) from None
    if args.png_level is not None and not 0 <= args.png_level <= 9:
        raise UserError(f"--png-level {args.png_level}: expected 0 to 9")
    if args.paper and args.rate is not None and args.rate != PAPER_RATE_HZ:
        raise UserError(f"--paper --rate {args.rate:g}: the paper's pairs are at {PAPER_RATE_HZ:g} Hz; leave out "
                        f"--rate, or --paper")
    if args.scheduler and args.engine != "dask":
        raise UserError("--scheduler needs --engine dask")
    try:
        topic_map = load_topic_map(args.topics) if args.topics else None
    except LayoutError as exc:
        raise UserError(str(exc)) from None
    rig = rig_from_args(args)
    extra = {"rate_hz": PAPER_RATE_HZ, "outputs": PAPER_OUTPUTS} if args.paper else {"rate_hz": args.rate}
    params = Params.from_rig(rig, tolerance_ms=args.tolerance_ms, ffc_margin=args.ffc_margin,
                             keep_ffc=args.keep_ffc, chunk_size=args.chunk_size, depth=args.depth,
                             png_compression_level=("rig" if args.png_level is None else args.png_level),
                             zed_images=args.zed_images or "rig", **extra)
    previous = signal.signal(signal.SIGTERM, _terminated)
    try:
        summary = export(args.recordings, args.out, rig, params, calibration=args.calibration, engine=args.engine,
                         workers=args.workers or usable_cpus(), scheduler=args.scheduler, recover=args.recover,
                         topic_map=topic_map, command=command_line(args))
    except ExportError as exc:
        raise UserError(str(exc)) from None
    except KeyboardInterrupt:
        error(f"{args.out}: interrupted; every worker stopped, the chunks already done are kept: run the same "
              f"command again to resume")
        return EXIT_INTERRUPTED
    finally:
        signal.signal(signal.SIGTERM, previous)
    if args.json:
        print_json(summary)
    elif not args.quiet:
        for r in summary["recordings"]:
            c = r["counts"]
            print(f"{r['name']}: {c['sampled']} samples from {c['zed_left_frames']} ZED frames "
                  f"({c['complete']} complete pairs, {c['ffc_dropped']} dropped for FFC)")
            print(f"{r['name']}: layout {r['layout']}; depth {r['depth']}; calibration: {r['calibration']['source']}")
        how = "already complete, " if summary["chunks_run"] == 0 else "resumed, " if summary["resumed"] else ""
        print(f"{summary['out']}: {summary['samples']} samples ({how}{summary['chunks_run']} of "
              f"{summary['chunks']} chunks run); index.csv, index.parquet")
    return 0
