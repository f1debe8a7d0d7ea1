"""Dataset pipeline benchmark, on one core, side by side with the targets of issue 9.

1. 16 -> 8-bit thermal at 640x512 (target >= 200 frames/s): this package's thermal8.to_8bit (histogram
   order statistics, lookup table, OpenCV CLAHE and bilateral) beside a direct transcription of the
   paper's code (np.sort for the percentiles, float64 arithmetic on the whole frame); same output.
2. Registration of a 1920x1200 depth map into 640x512 (target >= 10 frames/s): the numba kernel
   beside the plain numpy version (np.minimum.at / np.add.at) on the same inputs; same output.
   Inputs are the simulated rig's box scene rendered by ray casting at full resolution (a real depth
   map's coherence: random depths would measure cache misses, not the algorithm).

3. ``--export RECORDING``: the whole export (``platform_tools export ... --workers 2``) of previous code (the
   dataset package, its command export_cmd.py and the CLI's main.py, at a git revision, ``--previous REV``,
   default ``b7c0534``: the code issue 15 item 6 calls "today's"; repeat the option for several, e.g.
   ``--previous b7c0534 --previous HEAD``; each in a copy of this tree where only the export code differs)
   beside this tree's, on the same recording, alternating, after one untimed warm-up each at 0.25 Hz (numba
   compiles into each tree's cache); samples/s end to end (wall clock, indexing included) and the ratios, and the
   CPU seconds of each run (the command and its workers: what a shared machine's other load disturbs least); then
   every file of each previous output compared with this tree's (bytes; PNGs that differ are decoded and compared);
   each run writes into a new folder, all deleted when the bench ends (why: ``bench_export``). Each
   run's 1-minute load average, as it starts, is printed beside it (the machine may be shared). This tree runs
   with its default workers (forked on Linux); ``--spawn`` runs it again with spawned workers
   (``PLATFORM_TOOLS_EXPORT_WORKERS=spawn``) as ``new-spawn``, ``--fork`` with forked ones as ``new-fork`` (the
   default on Linux: for another system, or a tree whose default was spawn), ``--jit`` with numba's JIT kernels
   instead of the extension compiled ahead of time (``PLATFORM_TOOLS_KERNELS=jit``) as ``new-jit``. A previous tree
   that has platform_tools/dataset/kernels.py gets its extension built, as its bootstrap would build it; each
   tree's kernels are printed beside its runs. A full-size recording:
   ``platform_tools simulate-rig --out DIR --duration 12 --scale 1`` (``--duration 60`` for the steady state).

One core for 1 and 2: numba, OpenCV and BLAS are pinned to one thread before they load.
Before each timed run the recording's files are read once (into the page cache, whatever the machine let go since
the last run); ``--cold`` evicts them instead (``posix_fadvise``, no root needed): the export then reads them from
the disk, as it does a recording larger than the free memory.

4. ``--zstd RECORDING``: the thermal chunks' decompression alone, the system's libzstd (what the export uses,
   platform_tools/dataset/libzstd.py) beside python-zstandard's bundled one, interleaved, same bytes checked.

Run: .venv/bin/python bench/bench_dataset.py [--frames N] [--json] [--export RECORDING [--rate HZ] [--repeats N]
     [--spawn] [--fork] [--jit] [--cold]] [--zstd RECORDING [--chunks N]]
"""
from __future__ import annotations

import os

for var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from platform_tools.dataset import thermal8  # noqa: E402
from platform_tools.dataset.calib import load_calibration  # noqa: E402
from platform_tools.dataset.register import Registrar, register_numpy  # noqa: E402
from platform_tools.rig import load_rig  # noqa: E402
from platform_tools.sim import geometry  # noqa: E402

cv2.setNumThreads(1)


def paper_8bit(image_in: np.ndarray) -> np.ndarray:
    image_in = image_in.copy()
    if np.max(image_in) < 35000:
        out = (image_in - np.min(image_in)) / (np.max(image_in) - np.min(image_in)) * 255
    else:
        s = np.sort(image_in.reshape(-1))
        hi, lo = s[round(len(s) * 0.99) - 1], s[round(len(s) * 0.01)]
        img = np.clip(image_in, lo, hi)
        out = ((img - lo) / (hi - lo)) * 255.0
    clahe = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8)).apply(out.astype(np.uint8))
    return cv2.bilateralFilter(clahe, 5, 20, 15)


def rate(fn, n: int) -> float:
    fn()                                    # warm-up (numba compile, caches)
    t = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - t)


#: the export's code taken from git for a previous run: the dataset package, its command and the CLI's entry point
#: (which imported every command's module before they were made lazy)
PREVIOUS = ("platform_tools/dataset", "platform_tools/cli/export_cmd.py", "platform_tools/cli/main.py")
#: the code before issue 15 item 6's speed work ("today's" in the issue)
BASELINE = "b7c0534"


def previous_tree(tmp: Path, rev: str = BASELINE) -> Path:
    """A copy of this tree whose export code (PREVIOUS) is the one at git revision ``rev``."""
    import shutil
    import subprocess
    import tarfile
    tree = tmp / f"previous-{rev}"
    shutil.copytree(REPO, tree, ignore=shutil.ignore_patterns(".git", ".venv", "build", "__pycache__",
                                                              "*.egg-info", "node_modules"))
    shutil.rmtree(tree / "platform_tools" / "dataset")
    archive = subprocess.run(["git", "-C", str(REPO), "archive", "--format=tar", rev, *PREVIOUS],
                             check=True, capture_output=True).stdout
    with tarfile.open(fileobj=__import__("io").BytesIO(archive)) as tar:
        tar.extractall(tree)
    if _has_kernels(tree):                  # as its bootstrap would leave it
        subprocess.run([sys.executable, "-m", "platform_tools.dataset.kernels", "build"], cwd=tree,
                       env=tree_env(tree), check=True, capture_output=True)
    return tree


def _has_kernels(tree: Path) -> bool:
    """Whether ``tree`` has platform_tools.dataset.kernels (the kernels compiled ahead of time, since b1f20b4)."""
    return (tree / "platform_tools" / "dataset" / "kernels.py").is_file()


def tree_env(tree: Path, extra_env: dict | None = None) -> dict:
    """The environment a command of ``tree`` runs in: its code first on the path, this process's thread pins and
    export switches (FORK_ENV, KERNELS_ENV) dropped, then ``extra_env``."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    for var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", FORK_ENV,
                KERNELS_ENV):
        env.pop(var, None)
    return env | (extra_env or {})


def kernels_backend(tree: Path, extra_env: dict | None = None) -> str:
    """Which kernels ``tree``'s export uses in the environment its runs get (platform_tools.dataset.kernels:
    "extension ..." or "numba JIT"), or "numba JIT" for a tree from before that module."""
    import subprocess
    if not _has_kernels(tree):
        return "numba JIT"
    r = subprocess.run([sys.executable, "-m", "platform_tools.dataset.kernels", "status", "--json"], cwd=tree,
                       env=tree_env(tree, extra_env), check=True, capture_output=True, text=True)
    return json.loads(r.stdout)["backend"]


def run_export(tree: Path, recording: Path, out: Path, rate: float, workers: int,
               extra_env: dict | None = None) -> tuple[float, int, float, float]:
    """(wall seconds, samples, CPU seconds, the 1-minute load average as it starts) of one `platform_tools export`
    run with ``tree``'s code. The CPU time
    (user + system, of the command and its workers: getrusage of reaped children) is the figure a shared machine
    disturbs least: other users' load stretches the wall clock, not the work done."""
    import resource
    import subprocess
    if out.exists():
        raise SystemExit(f"{out}: exists; each run writes into a new folder (see bench_export)")
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = tree_env(tree, extra_env)
    cmd = [sys.executable, "-c", "import sys; from platform_tools.cli.main import main; sys.exit(main())",
           "export", str(recording), "--out", str(out), "--rate", str(rate), "--workers", str(workers),
           "--json", "-q"]
    load = os.getloadavg()[0]
    t = time.perf_counter()
    r = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t
    if r.returncode != 0:
        raise SystemExit(f"{tree}: export failed: {r.stderr.strip().splitlines()[-1:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (ru.ru_utime + ru.ru_stime)
    return dt, json.loads(r.stdout)["samples"], cpu, load


def compare_outputs(a: Path, b: Path) -> dict:
    """Every file of both outputs: identical bytes, or (PNG) identical pixels, or different. A PNG of ``a`` that is
    a JPEG of ``b`` (the same name but for the suffix: a compressed ZED image that ``b`` wrote as recorded,
    processing.zed_images) is compared by its pixels with the JPEG as OpenCV decodes it, which is how ``a`` made
    the PNG."""
    fa = {p.relative_to(a) for p in a.rglob("*") if p.is_file()}
    fb = {p.relative_to(b) for p in b.rglob("*") if p.is_file()}
    as_jpeg = {rel: rel.with_suffix(".jpg") for rel in fa - fb
               if rel.suffix == ".png" and rel.with_suffix(".jpg") in fb}
    res = {"files": len(fa), "only_in_previous": sorted(map(str, fa - fb - set(as_jpeg))),
           "only_in_new": sorted(map(str, fb - fa - set(as_jpeg.values()))),
           "identical_bytes": 0, "same_pixels": [], "same_pixels_as_jpeg": [], "different": []}
    for rel in sorted(fa & fb):
        if (a / rel).read_bytes() == (b / rel).read_bytes():
            res["identical_bytes"] += 1
        elif rel.suffix == ".png" and np.array_equal(cv2.imread(str(a / rel), cv2.IMREAD_UNCHANGED),
                                                     cv2.imread(str(b / rel), cv2.IMREAD_UNCHANGED)):
            res["same_pixels"].append(str(rel))
        else:
            res["different"].append(str(rel))
    for rel, jpg in sorted(as_jpeg.items()):
        same = np.array_equal(cv2.imread(str(a / rel), cv2.IMREAD_UNCHANGED),
                              cv2.imread(str(b / jpg), cv2.IMREAD_COLOR))
        res["same_pixels_as_jpeg" if same else "different"].append(str(jpg))
    return res


def evict(recording: Path) -> int | None:
    """Drop the recording's files from the page cache (``posix_fadvise(POSIX_FADV_DONTNEED)``: no root needed; the
    files are clean, long written), so that the next export reads them from the disk, as it does a recording larger
    than the free memory or read days after it was copied. The bytes of them still cached after it
    (:func:`_cached`)."""
    files = [f for f in Path(recording).rglob("*") if f.is_file()]
    for f in files:
        fd = os.open(f, os.O_RDONLY)
        try:
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        finally:
            os.close(fd)
    return _cached(files)


def preload(recording: Path) -> int | None:
    """Read the recording's files once, so that the next export finds them in the page cache (what the runs without
    ``--cold`` measure: the machine may have let part of them go since the last run, and the tree that reads more of
    the file would pay for it). The bytes of them cached after it (:func:`_cached`)."""
    files = [f for f in Path(recording).rglob("*") if f.is_file()]
    for f in files:
        with open(f, "rb", buffering=0) as fh:
            while fh.read(8 << 20):
                pass
    return _cached(files)


def _cached(files) -> int | None:
    """The bytes of ``files`` in the page cache, as util-linux's fincore counts them (None without fincore)."""
    import shutil
    import subprocess
    if not shutil.which("fincore"):
        return None
    out = subprocess.run(["fincore", "--bytes", "--noheadings", "--raw", "--output", "RES", *map(str, files)],
                         capture_output=True, text=True, check=True).stdout
    return sum(int(x) for x in out.split())


#: how this tree's export starts its workers (platform_tools.dataset.engines.START_ENV): "new-spawn" by --spawn,
#: "new-fork" by --fork; unset for "new" and for the previous trees
FORK_ENV = "PLATFORM_TOOLS_EXPORT_WORKERS"


#: which kernels an export uses (platform_tools.dataset.kernels.ENV): "jit" for "new-jit" (--jit); unset for the others
KERNELS_ENV = "PLATFORM_TOOLS_KERNELS"

#: the untimed warm-up export's rate: a few samples are enough for numba to fill a tree's cache (a fixed rate, so that
#: a long recording's warm-up stays short)
WARM_UP_RATE_HZ = 0.25


def paired_median(new_s: list, old_s: list, new_samples: int, old_samples: int) -> float:
    """The median over repeats of (samples/s of the new run) / (samples/s of the old run of the same repeat)."""
    import statistics
    return statistics.median((new_samples / a) / (old_samples / b) for a, b in zip(new_s, old_s))


def check_room(folder: Path, warm_outputs: list, scale: float, repeats: int) -> int:
    """The bytes the timed runs will write into ``folder``, estimated as each tree's warm-up output (``warm_outputs``)
    times ``scale`` (the timed runs' rate over the warm-up's) times ``repeats``, checked against the free space there
    (the outputs are kept until the bench ends, see :func:`bench_export`): a bench that would fill the disk stops
    before its first timed run, naming the folder and both figures. Returns the estimate."""
    import shutil
    wrote = sum(f.stat().st_size for out in warm_outputs for f in Path(out).rglob("*") if f.is_file())
    need = int(wrote * scale * repeats)
    free = shutil.disk_usage(folder).free
    if need > free:
        raise SystemExit(f"{folder}: the timed runs would write about {need / 1e6:,.1f} MB (kept until the bench ends) "
                         f"and {free / 1e6:,.1f} MB are free; fewer --repeats, a lower --rate, or more room")
    return need


def bench_export(recording: Path, rate: float, repeats: int, workers: int = 2, revs=(BASELINE,),
                 fork: bool = False, spawn: bool = False, cold: bool = False, jit: bool = False) -> dict:
    """``spawn`` / ``fork``: this tree a second time with its workers spawned ("new-spawn") / forked ("new-fork"),
    each run beside the others; ``jit``: this tree with numba's JIT kernels instead of the extension built ahead of
    time ("new-jit"). ``cold``: the recording evicted from the page cache before each timed run
    (:func:`evict`).

    Every run writes into a folder of its own, and none is deleted before the bench ends: on an ext4 file system
    without a journal (this project's machines: ``journal_task`` <none> in /sys/fs/ext4/DEV), a new inode is not
    given a number freed in the last 60 s (360 s while its inode table block is dirty); ext4's ``recently_deleted``
    test in ``find_inode_bit`` reads and skips each one. Deleting a run's output (743 files at 1 Hz) just before the
    next run made each new file's ``openat`` take 0.47 ms in the kernel, against 0.09 ms in a new folder (strace -T,
    medians, the same export of full60 at 1 Hz; perf: recently_deleted, find_get_block_common): about 0.3 s of CPU a
    run, in every tree alike, that an export into a new folder does not pay. A bench started within minutes of
    another one's end still meets the inodes that one freed."""
    import tempfile
    with tempfile.TemporaryDirectory(prefix="bench-export-") as tmp:
        tmp = Path(tmp)
        trees = {rev: (previous_tree(tmp, rev), {}) for rev in revs} | {"new": (REPO, {})}
        if spawn:
            trees["new-spawn"] = (REPO, {FORK_ENV: "spawn"})
        if fork:
            trees["new-fork"] = (REPO, {FORK_ENV: "fork"})
        if jit:
            trees["new-jit"] = (REPO, {KERNELS_ENV: "jit"})
        kernels = {name: kernels_backend(tree, env) for name, (tree, env) in trees.items()}
        for name, (tree, env) in trees.items():          # warm-up: numba compiles into each tree's cache
            run_export(tree, recording, tmp / f"warm-{name}", WARM_UP_RATE_HZ, workers, env)
        check_room(tmp, [tmp / f"warm-{n}" for n in trees], rate / WARM_UP_RATE_HZ, repeats)
        times = {n: [] for n in trees}
        cpu = {n: [] for n in trees}
        loads = {n: [] for n in trees}
        samples = {}
        resident = []
        for k in range(repeats):
            for name, (tree, env) in trees.items():
                resident.append(evict(recording) if cold else preload(recording))
                dt, samples[name], c, load = run_export(tree, recording, tmp / f"out-{name}-{k}", rate, workers,
                                                        env)                # a new folder: see the docstring
                times[name].append(dt)
                cpu[name].append(c)
                loads[name].append(load)
        sps = {n: samples[n] / min(t) for n, t in times.items()}
        ours = [n for n in trees if n.startswith("new")]
        return {"recording": str(recording), "rate_hz": rate, "workers": workers, "samples": samples,
                "kernels": kernels,
                "cold": cold, "resident_bytes_at_start": resident,
                "seconds": times, "samples_per_s": sps, "cpu_seconds": cpu, "load_average": loads,
                "ratio": {f"{n} / {rev}": sps[n] / sps[rev] for n in ours for rev in revs},
                "cpu_ratio": {f"{n} / {rev}": min(cpu[rev]) * samples[n] / (min(cpu[n]) * samples[rev])
                              for n in ours for rev in revs},
                # each repeat's two runs ran back to back: their ratio sees the same machine (a shared one drifts
                # by 10-20 % within minutes); the median of those is the figure its drift moves least
                "paired_ratio_median": {f"{n} / {rev}": paired_median(times[n], times[rev], samples[n], samples[rev])
                                        for n in ours for rev in revs},
                "outputs": {f"{n} / {rev}": compare_outputs(tmp / f"out-{rev}-{repeats - 1}",
                                                                          tmp / f"out-{n}-{repeats - 1}")
                            for n in ours for rev in revs}}


def bench_zstd(recording: Path, chunks: int, rounds: int) -> dict:
    """The export's chunk decompression (mcapscan -> libzstd.decompress: the system's libzstd) beside
    python-zstandard's, on the first ``chunks`` zstd chunks of ``recording`` that hold a thermal frame (what the
    index decompresses whole), ``rounds`` interleaved rounds; the outputs compared byte for byte."""
    import statistics
    import zstandard
    from mcap.reader import make_reader
    from platform_tools.dataset import libzstd, mcapscan
    from platform_tools.dataset.layout import detect
    from platform_tools.dataset.recording import mcap_files
    rig = load_rig()
    blobs = []
    for path in mcap_files(recording)[1]:
        with open(path, "rb") as fh:
            summary = make_reader(fh).get_summary()
            lay = detect(recording, {c.topic for c in summary.channels.values()}, rig)
            topics = {lay.topics[s] for s in ("thermal_left", "thermal_right") if s in lay.topics}
            thermal = {cid for cid, c in summary.channels.items() if c.topic in topics}
            for c in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
                if c.compression == "zstd" and thermal & set(c.message_index_offsets) and len(blobs) < chunks:
                    _, data, size = mcapscan._chunk_records(fh, c)
                    blobs.append((bytes(data), size))
    if not blobs:
        raise SystemExit(f"{recording}: no zstd chunk holding a thermal frame")
    total = sum(size for _, size in blobs)
    dz = zstandard.ZstdDecompressor()
    ways = {libzstd.backend(): lambda d, n: libzstd.decompress(d, n),
            "python-zstandard " + ".".join(map(str, zstandard.ZSTD_VERSION)):
                lambda d, n: dz.decompress(d, max_output_size=n)}
    for d, n in blobs:
        assert bytes(libzstd.decompress(d, n)) == dz.decompress(d, max_output_size=n)
    speeds = {k: [] for k in ways}
    for _ in range(rounds):
        for k, fn in ways.items():
            t = time.perf_counter()
            for d, n in blobs:
                fn(d, n)
            speeds[k].append(total / (time.perf_counter() - t) / 1e9)
    return {"recording": str(recording), "chunks": len(blobs), "uncompressed_mb": total / 1e6,
            "ratio": total / sum(len(d) for d, _ in blobs), "rounds": rounds,
            "gb_per_s": {k: statistics.median(v) for k, v in speeds.items()}, "runs_gb_per_s": speeds}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100, help="frames per 16->8-bit measurement (default 100)")
    ap.add_argument("--export", type=Path, metavar="RECORDING",
                    help="only the end-to-end export, previous code beside this tree's, on this recording")
    ap.add_argument("--rate", type=float, default=1.0, help="with --export: samples per second (default 1)")
    ap.add_argument("--repeats", type=int, default=2, help="with --export: timed runs of each (default 2; best kept)")
    ap.add_argument("--previous", action="append", metavar="REV",
                    help=f"with --export: the git revision of the previous code (repeatable; default {BASELINE})")
    ap.add_argument("--fork", action="store_true",
                    help=f"with --export: also this tree with its workers forked ({FORK_ENV}=fork), as new-fork")
    ap.add_argument("--jit", action="store_true",
                    help=f"with --export: also this tree with numba's JIT kernels ({KERNELS_ENV}=jit), as new-jit")
    ap.add_argument("--spawn", action="store_true",
                    help=f"with --export: also this tree with its workers spawned ({FORK_ENV}=spawn), as new-spawn")
    ap.add_argument("--cold", action="store_true",
                    help="with --export: the recording evicted from the page cache before each timed run, not read "
                         "into it (read from "
                         "the disk, as a recording larger than the free memory is)")
    ap.add_argument("--zstd", type=Path, metavar="RECORDING",
                    help="only the chunk decompression: the system's libzstd (what the export uses) beside "
                         "python-zstandard, on this recording's thermal chunks")
    ap.add_argument("--chunks", type=int, default=100, help="with --zstd: chunks decompressed per round (default 100)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.zstd:
        r = bench_zstd(args.zstd, args.chunks, rounds=9)
        if args.json:
            print(json.dumps(r, indent=2))
            return 0
        print(f"zstd decompression of {r['chunks']} thermal chunks of {r['recording']} ({r['uncompressed_mb']:.0f} MB, "
              f"ratio {r['ratio']:.2f}), median of {r['rounds']} interleaved rounds, same bytes:")
        for k, v in r["gb_per_s"].items():
            print(f"  {k:<34} {v:.3f} GB/s  (runs {min(r['runs_gb_per_s'][k]):.3f}-{max(r['runs_gb_per_s'][k]):.3f})")
        a, b = r["gb_per_s"].values()
        print(f"  ratio: {a / b:.2f}x")
        return 0
    if args.export:
        r = bench_export(args.export, args.rate, args.repeats, revs=tuple(args.previous or (BASELINE,)),
                         fork=args.fork, spawn=args.spawn, cold=args.cold, jit=args.jit)
        if args.json:
            print(json.dumps(r, indent=2))
            return 0
        known = [b for b in r["resident_bytes_at_start"] if b is not None]
        size = sum(f.stat().st_size for f in Path(r["recording"]).rglob("*") if f.is_file())
        if r["cold"]:
            cold = (", the recording evicted from the page cache before each run" +
                    (f" (at most {max(known) / 1e6:.1f} MB of it still cached, fincore)" if known else ""))
        else:
            cold = (", the recording read into the page cache before each run" +
                    (f" (at least {min(known) / 1e6:.0f} of its {size / 1e6:.0f} MB cached, fincore)" if known else ""))
        print(f"export of {r['recording']} at {r['rate_hz']:g} Hz, {r['workers']} workers, best of "
              f"{len(r['seconds']['new'])}{cold}:")
        for n in r["seconds"]:
            print(f"  {n:<10} {r['samples'][n]:>5} samples in {min(r['seconds'][n]):7.1f} s: "
                  f"{r['samples_per_s'][n]:6.2f} samples/s  (runs: {', '.join(f'{t:.1f}' for t in r['seconds'][n])} s;"
                  f" CPU {', '.join(f'{t:.1f}' for t in r['cpu_seconds'][n])} s; load average "
                  f"{', '.join(f'{t:.1f}' for t in r['load_average'][n])}; kernels: {r['kernels'][n]})")
        for pair, ratio in r["ratio"].items():
            o = r["outputs"][pair]
            ours, rev = pair.split(" / ")
            print(f"  ratio {pair}: {ratio:.2f}x in samples/s (wall clock), {r['cpu_ratio'][pair]:.2f}x in "
                  f"samples per CPU second (best runs); median of the {len(r['seconds']['new'])} back-to-back "
                  f"pairs: {r['paired_ratio_median'][pair]:.2f}x (wall clock)")
            print(f"    outputs: {o['files']} files, {o['identical_bytes']} identical bytes, {len(o['same_pixels'])} "
                  f"PNGs with other bytes but the same pixels, {len(o['same_pixels_as_jpeg'])} PNGs written as "
                  f"the recorded JPEG, with its pixels, {len(o['different'])} different "
                  f"({', '.join(o['different'][:5])}), only in {rev} {len(o['only_in_previous'])} "
                  f"({', '.join(o['only_in_previous'][:3])}), only in {ours} {len(o['only_in_new'])} "
                  f"({', '.join(o['only_in_new'][:3])})")
        return 0
    rig = load_rig()
    res = {}

    # 1. 16 -> 8 bit, both branches of the paper's rule (plain min-max; percentile clip above 35000)
    p = thermal8.Params.from_rig(rig)
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    th = geometry.sim_camera(rig, "thermal_left_optical", spec.width_px, spec.height_px)
    boxes = geometry.boxes_at(geometry.SCENE, 1.0)
    render = geometry.cast(th, geometry.rays_rig(th), boxes)
    counts = geometry.counts_from_c(geometry.temperature_c(render, boxes, geometry.SCENE))
    noise = np.random.default_rng(0).normal(0, 8, counts.shape)
    for label, offset in (("min-max", 0.0), ("percentile clip", 30000.0)):
        raw = np.clip(counts + offset + noise, 0, 65535).astype(np.uint16)
        assert np.array_equal(thermal8.to_8bit(raw, p)[0], paper_8bit(raw))
        ours = rate(lambda: thermal8.to_8bit(raw, p), args.frames)
        ref = rate(lambda: paper_8bit(raw), max(10, args.frames // 4))
        res[f"8bit {label}"] = {"ours_fps": ours, "paper_code_fps": ref, "ratio": ours / ref, "target_fps": 200}

    # 2. registration 1920x1200 -> 640x512
    zspec = rig.camera_model(rig.desc.sensors.zed_x.camera_model)
    zed = geometry.sim_camera(rig, "zed_x_left_optical", zspec.width_px, zspec.height_px)
    zr = geometry.cast(zed, geometry.rays_rig(zed), boxes)
    depth = geometry.zed_depth_m(zr, geometry.SCENE)
    bgr = geometry.colour(zr, boxes, geometry.SCENE)
    cal = load_calibration(rig)
    reg = Registrar(cal.cams["zed_x_left_optical"], cal.cams["thermal_left_optical"],
                    cal.rt_a_b("thermal_left_optical", "zed_x_left_optical"),
                    rig.desc.processing.zbuffer_tolerance_percent)
    a, b = reg.register(depth, bgr), register_numpy(reg, depth, bgr)
    assert np.array_equal(a.mask, b.mask) and np.allclose(a.image, b.image, atol=1e-3)
    ours = rate(lambda: reg.register(depth, bgr), 10)
    ref = rate(lambda: register_numpy(reg, depth, bgr), 2)
    res["registration 1920x1200 -> 640x512"] = {
        "ours_fps": ours, "numpy_add_at_fps": ref, "ratio": ours / ref, "target_fps": 10,
        "valid_depth_percent": float(np.isfinite(depth).mean() * 100), "registered_percent": float(a.mask.mean() * 100)}

    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    print(f"{'measurement (one core)':<36} {'ours f/s':>9} {'reference f/s':>14} {'ratio':>7} {'target':>7}")
    for name, r in res.items():
        ref = r.get("paper_code_fps", r.get("numpy_add_at_fps"))
        ok = "ok" if r["ours_fps"] >= r["target_fps"] else "MISSED"
        print(f"{name:<36} {r['ours_fps']:>9.1f} {ref:>14.2f} {r['ratio']:>6.1f}x {r['target_fps']:>5} {ok}")
    print("references: the paper's 16->8-bit code (np.sort percentiles, float64 frame); registration in plain "
          "numpy with np.minimum.at / np.add.at. Outputs checked identical before timing.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
