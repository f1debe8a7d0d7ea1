"""The export's compiled kernels (the registration's, :mod:`.register_kernels`, and the 8-bit conversion's lookup,
:func:`.thermal8._apply`): from an extension module compiled ahead of time from the same Python sources when one was
built for these sources on this CPU, else compiled by numba's JIT (cached on disk) on first use.

Why ahead of time: a process that imports numba and loads its registries spends about 0.3 s of CPU before its first
kernel runs, and the export pays it in each of its workers, on the path from the index to the first sample: 8 % of
the CPU of a full-size export at 1 Hz on 2 cores (docs/dataset.md "Speed"). The extension (``numba.pycc``) is
imported in under a millisecond, and a process that uses it never imports numba.

The extension is a file beside this module (or in ``$PLATFORM_TOOLS_KERNELS``) named by a key: ``_aot_kernels_<key>``
and the interpreter's extension suffix. The key hashes the kernels' sources, this module, numba's and Python's versions
and this CPU's name and features: the code is compiled for this CPU, as numba's own cache compiles it. A process whose
key names no file (a source edited since the build, numba upgraded, another CPU) uses the JIT: the same functions,
compiled the first time. ``python -m platform_tools.dataset.kernels build`` makes the file (the bootstrap runs it).

The extension's functions read their arguments as the signature says without checking them (a wrong dtype is a
crash, not a TypeError). :class:`Checked` calls one only with arrays of exactly the signature's dtype, dimensions
and C layout (writeable where the kernel writes) and with numbers where it takes numbers; any other call goes to
the JIT, which compiles a version for those types as it always did.

``PLATFORM_TOOLS_KERNELS=jit`` uses the JIT whatever is built; another value is the folder to look in instead of
this module's (tests, or an installation whose package folder is read-only).
"""
from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import os
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: the environment variable that chooses: "jit", or the folder holding the extension
ENV = "PLATFORM_TOOLS_KERNELS"
#: the extension's file name before its key
PREFIX = "_aot_kernels_"
#: how the interpreter names an extension module's file after its name (".cpython-311-x86_64-linux-gnu.so")
SUFFIX = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
HERE = Path(__file__).resolve().parent

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


@dataclass(frozen=True)
class Kernel:
    """One kernel: the numba function ``name`` of ``module`` (imported only to compile it; a plain Python function
    there is given to ``numba.njit``), with numba's types of its arguments and of its result, and the positions of
    the arrays it writes."""
    module: str
    name: str
    args: tuple
    result: str
    writes: frozenset

    def signature(self) -> str:
        return f"{self.result}({', '.join(self.args)})"


_REG = "platform_tools.dataset.register_kernels"
#: this module's name, whether imported or run (``python -m``: __name__ is "__main__" then)
_SELF = "platform_tools.dataset.kernels"
#: every kernel, by the name callers ask for; the types are those of the export's calls (chunk.process_chunk)
KERNELS = {
    "points_compact": Kernel(_REG, "_points_compact",
                             ("f4[:,::1]", "f8[:,:,::1]", "f8[:,::1]", "f8[::1]", "i8", "f8[::1]", "f8[:,::1]",
                              "i8", "i8", "f8[:,::1]", "i8[::1]", "i8[::1]", "i8[:,::1]"), "i8",
                             frozenset({9, 10, 11, 12})),
    "zbuffer": Kernel(_REG, "_zbuffer", ("f8[:,::1]", "i8", "i8", "i8", "f8[:,::1]"), "void", frozenset({4})),
    "blend_rows": Kernel(_REG, "_blend_rows",
                         ("f8[:,::1]", "i8[::1]", "u1[:,::1]", "i8", "i8", "f8", "f8[:,::1]", "i8[::1]", "i8[::1]",
                          "f8[:,:,::1]", "i8", "f8", "u1[:,:,::1]", "u1[:,::1]", "u2[:,::1]"), "i8",
                         frozenset({9, 12, 13, 14})),
    "apply_lut": Kernel("platform_tools.dataset.thermal8", "_apply", ("u2[::1]", "u1[::1]", "i8", "i8", "u1[::1]"),
                        "void", frozenset({4})),
}

#: modules whose values the kernels take in when they are compiled, beside the kernels' own: register's KIND_*
#: constants (register_kernels imports them; numba compiles a module's globals in as constants), so that a change there
#: changes the key too
BAKED_IN = frozenset({"platform_tools.dataset.register"})

#: numba's short scalar names in a signature -> numpy's
_DTYPES = {"f4": "float32", "f8": "float64", "i8": "int64", "u1": "uint8", "u2": "uint16"}


class KernelsError(RuntimeError):
    """The extension could not be built (no numba.pycc, no C compiler, a kernel numba cannot compile); one line."""


def _parse(spec: str) -> tuple[str, int]:
    """(numpy dtype name, dimensions) of one numba type of :data:`KERNELS` ("f8[:,::1]": float64, 2; "i8": int64, 0)."""
    base, _, dims = spec.partition("[")
    return _DTYPES[base], (dims.count(",") + 1 if dims else 0)


class Checked:
    """An extension kernel called only with the arguments its signature reads; any other call goes to ``fallback``
    (the JIT's dispatcher, made on first need)."""

    def __init__(self, function, kernel: Kernel, fallback):
        self.function, self.kernel, self._fallback = function, kernel, fallback
        self._specs = [(np.dtype(d), n, i in kernel.writes) for i, (d, n) in enumerate(map(_parse, kernel.args))]

    def fits(self, args: tuple) -> bool:
        """Whether ``args`` are what the extension's function reads: arrays of the signature's dtype (native byte
        order), dimensions and C layout, aligned, writeable where written; integers in int64's range for integers,
        real numbers for floats."""
        if len(args) != len(self._specs):
            return False
        for a, (dtype, ndim, written) in zip(args, self._specs):
            if ndim:
                if (type(a) is not np.ndarray or a.dtype != dtype or a.ndim != ndim or not a.flags.c_contiguous
                        or not a.flags.aligned or (written and not a.flags.writeable)):
                    return False
            elif dtype.kind == "i":
                if isinstance(a, bool) or not isinstance(a, (int, np.integer)) or not -2**63 <= int(a) < 2**63:
                    return False
            elif isinstance(a, bool) or not isinstance(a, (int, float, np.integer, np.floating)):
                return False
        return True

    def __call__(self, *args):
        if self.fits(args):
            return self.function(*args)
        return self._fallback()(*args)


_jitted: dict = {}      # name -> numba dispatcher
_loaded: dict = {}      # "module" -> the extension module, or None
_got: dict = {}         # name -> what get() returns


def jit(name: str):
    """Kernel ``name`` compiled by numba's JIT (its dispatcher; numba imported here, its registries loaded without
    scipy.linalg: engines.numba_without_blas_probe)."""
    if name not in _jitted:
        from .engines import numba_without_blas_probe
        numba_without_blas_probe()
        import numba
        kernel = KERNELS[name]
        fn = getattr(importlib.import_module(kernel.module), kernel.name)
        _jitted[name] = fn if hasattr(fn, "py_func") else numba.njit(cache=True)(fn)
    return _jitted[name]


def _cpu() -> str:
    """This CPU as LLVM names it, with its features (what numba's cache keys its files on too)."""
    import llvmlite.binding as llvm
    return f"{llvm.get_host_cpu_name()} {llvm.get_host_cpu_features().flatten()}"


def _numba_version() -> str:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("numba")
    except PackageNotFoundError:
        return "none"


def key() -> str:
    """The extension's key here: a hash of the kernels' source files, this module's and those of :data:`BAKED_IN`,
    numba's and Python's versions and this CPU (20 hexadecimal digits)."""
    h = hashlib.sha256()
    for module in sorted({k.module for k in KERNELS.values()} | {_SELF} | BAKED_IN):
        spec = importlib.util.find_spec(module)
        h.update(module.encode() + b"\0" + Path(spec.origin).read_bytes() + b"\0")
    h.update(f"{_numba_version()}\0{sys.version}\0{SUFFIX}\0{_cpu()}".encode())
    return h.hexdigest()[:20]


def folder() -> Path | None:
    """Where the extension is looked for (None: the JIT, by ``$PLATFORM_TOOLS_KERNELS=jit``)."""
    chosen = os.environ.get(ENV, "")
    if chosen == "jit":
        return None
    return Path(chosen) if chosen else HERE


def extension_path(directory: Path) -> Path:
    return directory / f"{PREFIX}{key()}{SUFFIX}"


def _extension():
    """The extension module built for this key, or None (none built, the JIT chosen, or a file that does not load:
    its error kept for :func:`backend`); loaded once."""
    if "module" not in _loaded:
        module = None
        directory = folder()
        if directory is not None:
            path = extension_path(directory)
            if path.is_file():
                try:
                    spec = importlib.util.spec_from_file_location(path.name[:-len(SUFFIX)], path)
                    module = importlib.util.module_from_spec(spec)
                    spec.loader.exec_module(module)
                except ImportError as exc:         # a damaged file: the JIT serves, status says why
                    _loaded["error"] = f"{path.name} did not load: {str(exc).splitlines()[0]}"
                    module = None
        _loaded["module"] = module
    return _loaded["module"]


def get(name: str):
    """Kernel ``name``: the extension's (through :class:`Checked`) when one is built for this key, else the JIT's;
    made once per process."""
    if name not in _got:
        module = _extension()
        _got[name] = jit(name) if module is None else Checked(getattr(module, name), KERNELS[name],
                                                               lambda: jit(name))
    return _got[name]


def backend() -> str:
    """Which kernels this process uses: ``extension <file>``, or ``numba JIT`` (with the reason when the extension
    for this key is there but did not load)."""
    module = _extension()
    if module is not None:
        return f"extension {Path(module.__file__).name}"
    return f"numba JIT ({_loaded['error']})" if "error" in _loaded else "numba JIT"


def _caller(dispatcher, n: int):
    """A Python function of ``n`` arguments that calls ``dispatcher`` with them (what numba.pycc compiles and exports:
    the kernel itself is compiled inside it with its own options, error_model among them)."""
    names = ", ".join(f"a{i}" for i in range(n))
    scope = {"kernel": dispatcher}
    exec(f"def call({names}):\n    return kernel({names})\n", scope)     # noqa: S102 - a fixed template
    return scope["call"]


def build(directory: Path | None = None, force: bool = False) -> tuple[Path, bool]:
    """Compile every kernel of :data:`KERNELS` into the extension for this key in ``directory`` (default: this
    module's folder): compiled in a temporary folder there, then renamed into place, so that a process never loads a
    file half-written. Then the extensions of other keys in that folder (named by :data:`PREFIX`, so written here
    before) are removed. Returns (its path, whether it was built now: False when it was there already and not
    ``force``). Raises :class:`KernelsError`."""
    directory = Path(directory) if directory is not None else HERE
    target = extension_path(directory)
    if target.is_file() and not force:
        return target, False
    import warnings
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # numba.pycc's pending deprecation (docs/dataset.md "Speed")
            from numba.pycc import CC
    except ImportError as exc:
        raise KernelsError(f"numba.pycc is not importable ({exc}): the kernels stay with numba's JIT") from None
    name = target.name[:-len(SUFFIX)]
    directory.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=directory, prefix=".aot-build-") as tmp:
        cc = CC(name)
        cc.output_dir = tmp
        cc.target_cpu = "host"
        cc.verbose = False
        for export, kernel in KERNELS.items():
            cc.export(export, kernel.signature())(_caller(jit(export), len(kernel.args)))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                cc.compile()
        except Exception as exc:            # noqa: BLE001 - numba, distutils and the compiler raise their own
            raise KernelsError(f"compiling the kernels failed: {type(exc).__name__}: {exc}".splitlines()[0]) from None
        built = Path(tmp) / target.name
        if not built.is_file():
            raise KernelsError(f"numba.pycc wrote no {target.name} in {tmp}")
        os.replace(built, target)
    for old in directory.glob(f"{PREFIX}*{SUFFIX}"):
        if old != target:
            old.unlink(missing_ok=True)
    return target, True


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m platform_tools.dataset.kernels",
        description="Compile the export's numba kernels ahead of time into one extension module (numba.pycc), so "
                    "that the export's workers need not import numba; or say which kernels this machine uses.",
        epilog="exit codes: 0 built, already built, or status printed; 1 the build failed (the export then uses "
               "numba's JIT: slower to start, the same results); 2 bad usage")
    sub = p.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build", help="build the extension for this key, unless it is built already")
    b.add_argument("--dir", type=Path, help="the folder to write it in (default: the package's)")
    b.add_argument("--force", action="store_true", help="build it again even if it is there")
    b.add_argument("--json", action="store_true", help="one JSON object on stdout")
    s = sub.add_parser("status", help="the key, the file it names and which kernels a process here uses")
    s.add_argument("--json", action="store_true", help="one JSON object on stdout")
    return p


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "status":
        directory = folder()
        path = extension_path(directory) if directory else None
        doc = {"key": key(), "extension": str(path) if path else None, "built": bool(path and path.is_file()),
               "backend": backend()}
        print(json.dumps(doc) if args.json else "\n".join(f"{k}: {v}" for k, v in doc.items()))
        return EXIT_OK
    t0 = time.perf_counter()
    try:
        path, made = build(args.dir, args.force)
    except (KernelsError, OSError) as exc:
        doc = {"ok": False, "error": str(exc)}
        print(json.dumps(doc) if args.json else f"kernels: {exc}", file=sys.stdout if args.json else sys.stderr)
        return EXIT_FAILED
    doc = {"ok": True, "extension": str(path), "built": made, "seconds": round(time.perf_counter() - t0, 1)}
    if args.json:
        print(json.dumps(doc))
    else:
        print(f"kernels: {'built' if made else 'already built'}: {path} ({doc['seconds']} s)")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
