"""Boson serial tooling benchmark: figures side by side with the targets of issue 5.

1. command round trips per second (bosonGetCameraSN) against an emulated Boson over a real pty,
   the emulator in its own process (`platform_tools boson-emulator`), as a camera would be;
2. `platform_tools boson-config --slave` on two emulated cameras, verify included: the whole command
   as a user runs it (a new process) and the configure work alone (in-process main());
3. correctness of flirpy-style framing (sequence always 0; header and CRC not escaped) against this
   tool's framing, over every command of the table and many sequence numbers: the share of request
   frames a camera would mis-read. There is no other tool runnable here, so the comparison is of
   correctness, not speed.

4. the two-camera set-up (`boson-config --slave`, a new process, the same emulators in their own
   process) by this code and by the previous Boson code (`git archive HEAD` of platform_tools/boson and
   the boson commands, i.e. before issue 17's changes, over a copy of the rest of this tree), without faults, on a noisy link, and on a slow camera (every reply
   0.5 s late with --timeout 0.33: the issue's 1.5 s camera with the default 1 s timeout, scaled by 1/3).

Run: .venv/bin/python bench/bench_boson.py [--round-trips N] [--base-rev REV]
"""
from __future__ import annotations

import argparse
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import redirect_stdout
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from platform_tools.boson import commands as C, fslp  # noqa: E402
from platform_tools.boson.client import BosonClient, Timeouts  # noqa: E402
from platform_tools.boson.transport import SerialTransport  # noqa: E402

PT = [sys.executable, "-m", "platform_tools.cli.main"]
SERIALS = (93588, 93589)
RIG = ["--set", f"sensors.thermal.left.serial={SERIALS[0]}", "--set", f"sensors.thermal.right.serial={SERIALS[1]}"]


def start_emulators(by_id: str) -> subprocess.Popen:
    proc = subprocess.Popen(PT + ["boson-emulator", "--by-id-dir", by_id, "--serial", str(SERIALS[0]),
                                  "--serial", str(SERIALS[1])], cwd=REPO, stdout=subprocess.PIPE, text=True)
    for _ in SERIALS:
        proc.stdout.readline()
    return proc


def reset_emulators(by_id: str) -> None:
    """Back to factory sync and telemetry, so every timed run has the same changes to make."""
    for sn in SERIALS:
        with BosonClient(SerialTransport(f"{by_id}/usb-FLIR_Boson_{sn}-if00"), retries=10) as c:
            c.call(C.SET_EXT_SYNC, "disable")
            c.call(C.SET_TELEMETRY, "disabled")
            c.call(C.SET_TELEMETRY_LOCATION, "top")


def bench_round_trips(by_id: str, n: int) -> float:
    with BosonClient(SerialTransport(f"{by_id}/usb-FLIR_Boson_{SERIALS[0]}-if00"), timeouts=Timeouts()) as c:
        for _ in range(50):
            c.call(C.GET_CAMERA_SN)
        t0 = time.perf_counter()
        for _ in range(n):
            c.call(C.GET_CAMERA_SN)
        return n / (time.perf_counter() - t0)


def bench_config_process(by_id: str, runs: int) -> tuple[float, float]:
    env = dict(os.environ, PLATFORM_TOOLS_BOSON_BY_ID=by_id)
    times = []
    for _ in range(runs):
        reset_emulators(by_id)
        t0 = time.perf_counter()
        r = subprocess.run(PT + ["boson-config", "--slave", *RIG, "--json"], cwd=REPO, env=env,
                           capture_output=True, text=True)
        times.append(time.perf_counter() - t0)
        doc = json.loads(r.stdout)
        assert r.returncode == 0 and all(c["status"] == "configured" for c in doc["cameras"]), r.stderr
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import platform_tools.cli.main"], cwd=REPO, check=True)
    startup = time.perf_counter() - t0
    return min(times), startup


def bench_config_inprocess(by_id: str, runs: int) -> float:
    from platform_tools.cli.main import main
    os.environ["PLATFORM_TOOLS_BOSON_BY_ID"] = by_id
    times = []
    for _ in range(runs):
        reset_emulators(by_id)
        buf = io.StringIO()
        t0 = time.perf_counter()
        with redirect_stdout(buf):
            code = main(["boson-config", "--slave", *RIG, "--json", "-q"])
        times.append(time.perf_counter() - t0)
        assert code == 0 and json.loads(buf.getvalue())["ok"]
    return min(times)


#: link conditions of the set-up comparison: name -> (emulator --faults, extra boson-config options)
SETUP_CASES = {
    "no faults": ("", []),
    "noisy link (split, garbage, stale, bad CRC, busy)":
        ("split,garbage:p=0.3,wrongseq:p=0.3,badcrc:p=0.2,busy:p=0.2", ["--retries", "6"]),
    "slow camera (0.5 s replies, --timeout 0.33)": ("delay:s=0.5", ["--timeout", "0.33"]),
}


def export_base(rev: str, into: str) -> str:
    """The previous Boson code on today's everything else: a copy of this tree's platform_tools and config,
    with platform_tools/boson and the two boson commands replaced by ``rev``'s (read-only git: `git
    archive`), so the comparison is of the Boson code alone, not of the rig loader or rig.yaml."""
    shutil.copytree(REPO / "platform_tools", Path(into) / "platform_tools",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(REPO / "config", Path(into) / "config")
    shutil.rmtree(Path(into) / "platform_tools" / "boson")
    data = subprocess.run(["git", "archive", rev, "platform_tools/boson", "platform_tools/cli/boson_cmd.py",
                           "platform_tools/cli/boson_emulator_cmd.py"], cwd=REPO, capture_output=True,
                          check=True).stdout
    subprocess.run(["tar", "-x", "-C", into], input=data, check=True)
    return into


def _requests(log: Path) -> int:
    """Requests the emulators received so far (their session log)."""
    try:
        return sum(1 for line in log.read_text().splitlines() if '"dir": "rx"' in line)
    except OSError:
        return 0


def bench_setup_cases(base_dir: str, runs: int) -> list[tuple]:
    """(case, this code s, exit, requests per camera, previous code s, exit, requests per camera): the best
    of ``runs`` seconds, emulators restarted per case."""
    out = []
    for name, (faults, extra) in SETUP_CASES.items():
        with tempfile.TemporaryDirectory(prefix="bench-boson-setup.") as by_id:
            log = Path(by_id) / "session.log"
            cmd = PT + ["boson-emulator", "--by-id-dir", by_id, "--serial", str(SERIALS[0]), "--serial",
                        str(SERIALS[1]), "--log", str(log)] + (["--faults", faults] if faults else [])
            proc = subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.PIPE, text=True)
            for _ in SERIALS:
                proc.stdout.readline()
            try:
                row = [name]
                for where in (str(REPO), base_dir):
                    env = dict(os.environ, PLATFORM_TOOLS_BOSON_BY_ID=by_id, PYTHONPATH=where)
                    best, code, requests = float("inf"), None, 0
                    for _ in range(runs):
                        reset_emulators(by_id)
                        n0 = _requests(log)
                        t0 = time.perf_counter()
                        r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "boson-config",
                                            "--slave", *RIG, *extra, "--json"], cwd=where, env=env,
                                           capture_output=True, text=True)
                        best, code = min(best, time.perf_counter() - t0), r.returncode
                        requests = _requests(log) - n0
                    row += [best, code, requests / len(SERIALS)]
                out.append(tuple(row))
            finally:
                proc.terminate()
                proc.wait(timeout=10)
    return out


def flirpy_style_frame(seq: int, fid: int, payload: bytes) -> bytes:
    """As the reference describes flirpy: header and CRC sent unescaped (payload escaped)."""
    header = bytes([0]) + seq.to_bytes(4, "big") + fid.to_bytes(4, "big") + (0xFFFFFFFF).to_bytes(4, "big")
    crc = fslp.crc16(header + payload).to_bytes(2, "big")
    return bytes([fslp.START]) + header + fslp.escape(payload) + crc + bytes([fslp.END])


def decodes_to(raw: bytes, seq: int, fid: int, payload: bytes) -> bool:
    items = fslp.StreamDecoder().feed(raw)
    return items == [fslp.Frame(0, seq, fid, fslp.STATUS_REQUEST, payload)]


def framing_correctness(n_sequences: int) -> dict:
    cases = []
    for cmd in C.BY_ID.values():
        payloads = [cmd.encode_request(v) for v in range(0, 5)] if cmd.request else [b""]
        cases += [(cmd.function_id, p) for p in payloads]
    ours_bad = flirpy_bad = 0
    for fid, payload in cases:
        ours_bad += not decodes_to(fslp.request(1, fid, payload), 1, fid, payload)
        flirpy_bad += not decodes_to(flirpy_style_frame(0, fid, payload), 0, fid, payload)
    import random
    rng = random.Random(5)
    rand = [rng.randbytes(4) for _ in range(5000)]
    rand_ours = sum(not decodes_to(fslp.request(1, 0x00050098, p), 1, 0x00050098, p) for p in rand)
    rand_flirpy = sum(not decodes_to(flirpy_style_frame(0, 0x00050098, p), 0, 0x00050098, p) for p in rand)
    # sequence numbers: this tool skips values with special bytes and escapes anyway; an unescaping
    # tool that incremented its sequence would break on every value containing 8E/9E/AE or whose CRC does
    seq_bad_unescaped = sum(not decodes_to(flirpy_style_frame(s, 0x00050002, b""), s, 0x00050002, b"")
                            for s in range(1, n_sequences + 1))
    seq, seq_bad_ours = 0, 0
    for _ in range(n_sequences):
        seq = fslp.next_sequence(seq)
        seq_bad_ours += not decodes_to(fslp.request(seq, 0x00050002), seq, 0x00050002, b"")
    return {"cases": len(cases), "ours_bad": ours_bad, "flirpy_bad": flirpy_bad,
            "random": len(rand), "rand_ours": rand_ours, "rand_flirpy": rand_flirpy, "sequences": n_sequences, "seq_bad_unescaped": seq_bad_unescaped, "seq_bad_ours": seq_bad_ours}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--round-trips", type=int, default=3000)
    ap.add_argument("--config-runs", type=int, default=3)
    ap.add_argument("--base-rev", default="HEAD", help="the previous code to compare the set-up with")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-boson-base.") as base:
        setup = bench_setup_cases(export_base(args.base_rev, base), runs=3)
    with tempfile.TemporaryDirectory(prefix="bench-boson.") as by_id:
        proc = start_emulators(by_id)
        try:
            rate = bench_round_trips(by_id, args.round_trips)
            cfg_proc, startup = bench_config_process(by_id, args.config_runs)
            cfg_inproc = bench_config_inprocess(by_id, args.config_runs)
        finally:
            proc.terminate()
            proc.wait(timeout=10)
    fr = framing_correctness(20000)
    print("Boson serial tooling benchmark (emulated Bosons over real ptys, emulator in its own process)\n")
    print(f"{'measure':58s} {'this tool':>14s} {'target':>12s} {'ratio':>8s}")
    print(f"{'command round trips per second (bosonGetCameraSN)':58s} {rate:14.0f} {'>= 500':>12s} "
          f"{rate / 500:7.1f}x")
    print(f"{'boson-config --slave, 2 cameras, verify, new process (s)':58s} {cfg_proc:14.3f} {'< 1.0':>12s} "
          f"{1.0 / cfg_proc:7.1f}x")
    print(f"{'  of which Python start-up and imports (s)':58s} {startup:14.3f}")
    print(f"{'boson-config --slave, 2 cameras, verify, in-process (s)':58s} {cfg_inproc:14.3f} {'< 1.0':>12s} "
          f"{1.0 / cfg_inproc:7.1f}x")
    print(f"\nTwo-camera set-up, boson-config --slave, new process, best of 3 (s; exit code), previous code = "
          f"{args.base_rev}:")
    print(f"{'link':52s} {'this code':>20s} {'previous':>20s} {'ratio':>6s}")
    for name, ours, code, n_ours, base_s, base_code, n_base in setup:
        print(f"{name:52s} {ours:6.2f} ({code}) {n_ours:4.0f} req {base_s:6.2f} ({base_code}) {n_base:4.0f} req "
              f"{base_s / ours:5.2f}x")
    print("(req: requests each camera received in the last run, the reset before it not counted; this code "
          "asks each port its serial and reads back every setting)")
    print("\nFraming correctness (request frames a camera would mis-read, counts; no reference tool runs here):")
    print(f"{'':58s} {'this tool':>14s} {'flirpy-style':>12s}")
    print(f"{'every command x 5 payload values, sequence 0 / 1 (%d frames)' % fr['cases']:58s} "
          f"{fr['ours_bad']:>14d} {fr['flirpy_bad']:>12d}")
    print(f"{'random 4-byte payloads, %d frames (e.g. boson-raw)' % fr['random']:58s} "
          f"{fr['rand_ours']:>14d} {fr['rand_flirpy']:>12d}")
    print(f"{'sequence numbers 1..%d, header and CRC unescaped' % fr['sequences']:58s} "
          f"{fr['seq_bad_ours']:>14d} {fr['seq_bad_unescaped']:>12d}")
    print("flirpy-style also fixes the sequence at 0, so a late reply to an earlier command cannot be told "
          "from the reply to the current one;\nthis tool matches sequence and function id and discards the rest "
          "(tests/boson/test_client.py::test_faults_are_recovered[wrongseq]).")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
