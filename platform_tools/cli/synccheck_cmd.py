"""`platform_tools sync-check RECORDING`: can this recording's frames be trusted to pair?"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sync-check", help="sync analysis of a recording: drops, FFC, pairing residuals, verdict",
                       description="Per stream: frame intervals, drops (interval above "
                                   "processing.sync_limits.drop_interval_factor x the nominal period) and the "
                                   "jitter; FFC periods; clock steps of the host; which trigger pulse exposed "
                                   "every thermal frame (its offset after the ZED, uncertainty and evidence: the "
                                   "stated latency, trigger gaps, the Boson frame counter, continuity across a "
                                   "step); the clock steps of each stream (when, which clocks, how big, and how a "
                                   "step known modulo a trigger period was sized: the IMU, the frame counter, the "
                                   "recorder's log times); the jitter and drift (ppm) of the frames of one trigger, clock steps "
                                   "taken out. Pass/fail against processing.sync_limits (change them with --set "
                                   "processing.sync_limits.KEY=VALUE). Exit 0 pass, 1 a check failed (an "
                                   "ambiguous trigger included), 2 bad input.")
    p.add_argument("recording", metavar="RECORDING", type=Path,
                   help="a rosbag2 folder, a folder holding one (simulate-rig's DIR), or an .mcap file")
    p.add_argument("--plots", metavar="DIR", type=Path, help="write SVG plots (interval histograms, residuals "
                                                             "over time with FFC marked) and report.json there")
    p.add_argument("--recover", action="store_true",
                   help="salvage a truncated MCAP into NAME.recovered.mcap beside it (the original is kept)")
    p.add_argument("--topics", metavar="FILE", type=Path,
                   help="a YAML topic map (stream: /topic) for a recording in neither this rig's layout nor the "
                        "TartanRGBT stack's (both detected without it)")
    p.add_argument("--calibration", metavar="DIR", type=Path,
                   help="report this folder of .cameramodel files as the calibration (default: the recording's "
                        "camera_info, else the rig's nominal models); the export uses the same rule")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes that read the recording's chunks side by side (default: the CPUs this process "
                        "may use; 1: this process alone); on 2 cores 2 take about half the time of 1")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_sync_check)


def _plots(report: dict, out: Path, rig) -> list[str]:
    import json

    from platform_tools.rig import atomic
    from ..dataset import svgplot
    period_ms = 1000.0 / rig.desc.sync.rate_hz
    factor = report["limits"]["drop_interval_factor"]
    times = report["_times"]
    t0 = min(int(t[0]) for t in times.values() if len(t))
    written = []
    with atomic.OutputDir(out) as stage:
        for name, t in times.items():
            if name == "zed_depth":
                continue
            (stage / f"intervals_{name}.svg").write_text(
                svgplot.interval_histogram(name, np.diff(np.sort(t)) / 1e6, period_ms, factor))
            written.append(f"intervals_{name}.svg")
        for name, (t, r) in report["_series"].items():
            spans = []
            for cam in ("thermal_left", "thermal_right"):
                if cam in name:
                    spans += [((e["start_ns"] - t0) / 1e9, (e["end_ns"] - t0) / 1e9, f"FFC {cam}")
                              for e in report["ffc"][cam]]
            (stage / f"residuals_{name}.svg").write_text(svgplot.residual_series(
                name, (t - t0) / 1e9, r / 1e6, spans, report["pairs"][name]["offset_ms"]))
            written.append(f"residuals_{name}.svg")
        (stage / "report.json").write_text(json.dumps(_public(report), indent=2) + "\n")
        written.append("report.json")
    return [str(out / w) for w in written]


def _public(report: dict) -> dict:
    return {k: v for k, v in report.items() if not k.startswith("_")}


def _fmt(v, spec=".2f") -> str:
    return "-" if v is None else format(v, spec)


def cmd_sync_check(args: argparse.Namespace) -> int:
    from ..dataset.calib import CalibrationError, for_recording
    from ..dataset.layout import LayoutError, load_topic_map
    from ..dataset.recording import RecordingError, open_recording
    from ..dataset.sync import Limits, analyse
    from ..dataset.engines import EngineError, started, stdlib_distutils, usable_cpus
    rig = rig_from_args(args)
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers {args.workers}: expected 1 or more")
    try:
        topic_map = load_topic_map(args.topics) if args.topics else None
        with started("pool", args.workers or usable_cpus()) as pool:
            rec = open_recording(args.recording, rig, recover=args.recover, topic_map=topic_map, pool=pool)
        report = analyse(rec, rig, Limits.from_rig(rig))
        with stdlib_distutils():          # mrcal imported without setuptools' distutils (engines.stdlib_distutils)
            cal = for_recording(rig, rec, args.calibration)
    except (RecordingError, LayoutError, CalibrationError, EngineError) as exc:
        raise UserError(str(exc)) from None
    report["layout"] = rec.layout
    report["calibration"] = cal.to_dict()
    report["depth"] = rec.streams["zed_depth"].topic if rec.has("zed_depth") else None
    if args.plots:
        report["plots"] = _plots(report, args.plots, rig)
    if args.json:
        print_json(_public(report))
    elif not args.quiet:
        print(f"{rec.path}: {report['verdict'].upper()}")
        print(f"layout {rec.layout}; calibration: {cal.source}"
              + ("" if report["depth"] else "; no depth topic (sync only: the export needs depth)"))
        print(f"{'stream':<15} {'frames':>7} {'mean ms':>8} {'std ms':>7} {'max ms':>7} {'jitter':>7} "
              f"{'drops':>6} {'missing':>8}")
        for name, s in report["streams"].items():
            iv = s["interval_ms"]
            d = s.get("drops", {})
            print(f"{name:<15} {s['frames']:>7} {_fmt(iv['mean']):>8} {_fmt(iv['std']):>7} {_fmt(iv['max']):>7} "
                  f"{_fmt(s.get('jitter_ms'), '.3f'):>7} {d.get('events', '-'):>6} {d.get('missing_frames', '-'):>8}")
        for st in report["clock_steps"]:
            print(f"clock step: {st['step_ns'] / 1e6:+.3f} ms at stamp {st['at_ns']} (found on {st['found_on']})")
            for clock, c in (st.get("clocks") or {}).items():     # per stream: its size and how it was chosen
                size = (f"{c['step_ms']:+.1f} ms, sized by the {c['sized_by']}" if c["exact"] else
                        f"{c['step_ms']:+.1f} ms modulo one period: candidates "
                        + ", ".join(f"{x:+.1f}" for x in c["candidates_ms"]) + " ms (0, 1, 2... frames lost at it)")
                print(f"  {clock}: {size}" + (f" ({c['evidence']})" if c["evidence"] else ""))
        for cam, periods in report["ffc"].items():
            for e in periods:
                print(f"FFC {cam}: {(e['end_ns'] - e['start_ns']) / 1e9:.2f} s from stamp {e['start_ns']} "
                      f"({e['source']})")
        for cam, tr in (report.get("triggers") or {}).items():
            for g in tr.get("segments", []):
                print(f"trigger {cam} frames {g['frames'][0]}..{g['frames'][1]}: {g['offset_ms']:.2f} "
                      f"+- {g['uncertainty_ms']:.2f} ms after the ZED's trigger ({g['established_by']})")
        by_trigger = report.get("pairs_by_trigger") or {}
        if by_trigger:
            print("frames of the same trigger pulse (each stream's clock steps taken out):")
            print(f"{'pair':<28} {'n':>5} {'segments':>8} {'jitter p99 ms':>13} {'drift ppm':>18}")
            for name, p in by_trigger.items():
                print(f"{name:<28} {p['pairs']:>5} {p.get('segments', '-'):>8} {_fmt(p['jitter_p99_ms'], '.3f'):>13} "
                      f"{_fmt(p['drift_ppm'], '.1f'):>9} +- {_fmt(p['drift_stderr_ppm'], '.1f'):<6}")
        else:     # no trigger assignment: only the nearest-stamp statistics (an offset over half a period aliases)
            print("nearest-stamp residuals (the trigger of each frame is not established: no pairing)")
            print(f"{'pair':<28} {'n':>5} {'std':>6} {'p99':>7} {'jit99':>6} {'ppm':>7}")
            for name, p in report["pairs"].items():
                r = p["residual_ms"] or {}
                print(f"{name:<28} {p['pairs']:>5} {_fmt(r.get('std')):>6} {_fmt(r.get('p99')):>7} "
                      f"{_fmt(p['jitter_p99_ms']):>6} {_fmt(p['drift_ppm'], '.1f'):>7}")
        for c in report["checks"]:
            if not c["ok"]:
                print(f"FAIL {c['check']}: {c['value']} {c['unit']} (limit {c['limit']})")
        for p in report.get("plots", []):
            print(p)
    return 0 if report["verdict"] == "pass" else 1
