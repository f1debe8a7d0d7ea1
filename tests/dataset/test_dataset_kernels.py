"""The export's kernels compiled ahead of time (platform_tools.dataset.kernels): the extension gives numba's JIT's
results to the bit, a process using it never imports numba, a key that names no file falls back to the JIT, a call
whose arguments are not exactly the signature's goes to the JIT instead of the extension (which would read them as
the signature says: a crash), and the build replaces only the files it wrote. The extension is built into a
temporary folder by the command the bootstrap runs; the comparisons run in fresh interpreters, one per backend."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from platform_tools.dataset import kernels
from tests.conftest import REPO


def _run(args: list[str], env_kernels: str | None, **kw) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != kernels.ENV}
    if env_kernels is not None:
        env[kernels.ENV] = env_kernels
    return subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True, text=True, timeout=600, env=env,
                          **kw)


#: in a fresh interpreter: registrations through each lens kind the kernels project (pinhole, stereographic, OpenCV;
#: two surfaces, sky without depth, points past the image's rim) in three colours and in one, the 8-bit conversion of
#: frames that take the min-max and the clipped path, all saved to argv[1]; with the backend and whether numba was
#: imported
_OUTPUTS = """
import json, sys
import numpy as np, mrcal
from platform_tools.dataset import kernels, thermal8
from platform_tools.dataset.register import Registrar
from platform_tools.rig import load_rig
rng = np.random.default_rng(11)
zed = mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([300.0, 300.0, 159.5, 119.5])),
                        imagersize=np.array([320, 240]))
lenses = [("LENSMODEL_PINHOLE", [260.0, 262.0, 127.5, 101.5]),
          ("LENSMODEL_STEREOGRAPHIC", [180.0, 181.0, 128.3, 102.1]),
          ("LENSMODEL_OPENCV8", [240.0, 241.0, 126.0, 103.0, -0.21, 0.05, 1e-3, -2e-3, 0.01, 0.02, -0.01, 0.003])]
depth = np.where(rng.random((240, 320)) < 0.1, np.nan, 3.0 + np.cumsum(rng.normal(0, 0.01, (240, 320)), 1))
depth[60:140, 80:200] = 1.2 + rng.uniform(0, 0.02, (80, 120))      # a near surface over the far one
depth = depth.astype(np.float32)
bgr = rng.integers(0, 256, (240, 320, 3), dtype=np.uint8)
out = {}
for k, (lens, intr) in enumerate(lenses):
    th = mrcal.cameramodel(intrinsics=(lens, np.array(intr)), imagersize=np.array([256, 204]))
    reg = Registrar(zed, th, np.array([0.01, -0.02, 0.005, 0.06, 0.01, 0.0]), 2.0, 0.5)
    for c, src in (("bgr", bgr), ("mono", np.ascontiguousarray(bgr[..., 1]))):
        got = reg.register_u8(depth, src)
        out[f"{k}{c}_image"], out[f"{k}{c}_mask"], out[f"{k}{c}_depth"] = got.image, got.mask, got.depth_mm
        out[f"{k}{c}_fraction"] = np.array(got.fraction)
p8 = thermal8.Params.from_rig(load_rig())
for k, top in enumerate((30000, 60000)):
    raw = rng.integers(20000, top, (512, 640)).astype(np.uint16)
    out[f"t8_{k}"] = thermal8.to_8bit(raw, p8)[0]
np.savez(sys.argv[1], **out)
print(json.dumps({"backend": kernels.backend(), "numba": "numba" in sys.modules}))
"""


@pytest.mark.slow
def test_the_extension_gives_the_jits_results_to_the_bit_without_numba(built, tmp_path):
    docs = {}
    for name, env in (("jit", "jit"), ("extension", str(built))):
        r = _run(["-c", _OUTPUTS, str(tmp_path / f"{name}.npz")], env)
        assert r.returncode == 0, r.stderr
        docs[name] = json.loads(r.stdout.strip().splitlines()[-1])
    assert docs["jit"] == {"backend": "numba JIT", "numba": True}
    assert docs["extension"]["backend"].startswith("extension _aot_kernels_") and docs["extension"]["numba"] is False
    a, b = np.load(tmp_path / "jit.npz"), np.load(tmp_path / "extension.npz")
    assert sorted(a.files) == sorted(b.files) and len(a.files) == 3 * 2 * 4 + 2
    for f in a.files:
        assert a[f].dtype == b[f].dtype and np.array_equal(a[f], b[f]), f
    for k in range(3):                       # the scene is not trivial in any lens: valid, invalid, both surfaces
        assert 0.2 < float(a[f"{k}bgr_fraction"]) < 0.95
        near = a[f"{k}bgr_depth"][a[f"{k}bgr_mask"] > 0]
        assert (near < 1300).any() and (near > 2500).any()


def test_a_key_that_names_no_file_uses_the_jit(built, tmp_path):
    """An extension whose key is not this process's (built for other sources, another numba or another CPU) is not
    loaded: the status says so and the kernels are the JIT's."""
    other = tmp_path / "other"
    other.mkdir()
    ext = next(built.iterdir())
    shutil.copy(ext, other / ext.name.replace(ext.name[len(kernels.PREFIX):][:20], "0" * 20))
    r = _run(["-m", "platform_tools.dataset.kernels", "status", "--json"], str(other))
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["built"] is False and doc["backend"] == "numba JIT" and doc["key"] != "0" * 20
    r = _run(["-m", "platform_tools.dataset.kernels", "status", "--json"], str(built))
    assert json.loads(r.stdout)["built"] is True and json.loads(r.stdout)["key"] in ext.name


def test_an_extension_that_does_not_load_leaves_the_jit_and_says_why(built, tmp_path):
    """A file with this key's name that is no extension (a damaged build): the kernels are the JIT's, and the status
    names the file and the loader's error instead of failing."""
    damaged = tmp_path / "damaged"
    damaged.mkdir()
    (damaged / next(built.iterdir()).name).write_bytes(b"not an ELF file")
    code = ("import json, numpy as np\n"
            "from platform_tools.dataset import kernels\n"
            "raw, out = np.arange(6, dtype=np.uint16), np.zeros(6, np.uint8)\n"
            "kernels.get('apply_lut')(raw, np.array([10, 20, 30], np.uint8), 2, 4, out)\n"
            "print(json.dumps({'backend': kernels.backend(), 'out': out.tolist()}))\n")
    r = _run(["-c", code], str(damaged))
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["out"] == [10, 10, 10, 20, 30, 30]
    assert doc["backend"].startswith("numba JIT (") and next(built.iterdir()).name in doc["backend"]
    assert "did not load" in doc["backend"]


def test_the_key_follows_the_kernels_sources(tmp_path):
    """A kernel's source edited (one comment line) gives another key, so the extension built before it is not used;
    so does register.py, whose constants the kernels compile in."""
    copy = tmp_path / "tree"
    shutil.copytree(REPO / "platform_tools", copy / "platform_tools",
                    ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    code = "from platform_tools.dataset import kernels; print(kernels.key())"
    keys = []
    for edit in (None, "register_kernels.py", "register.py"):
        if edit:
            src = copy / "platform_tools" / "dataset" / edit
            src.write_text(src.read_text() + "# edited\n")
        r = subprocess.run([sys.executable, "-c", code], cwd=copy, capture_output=True, text=True, timeout=120,
                           env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
        assert r.returncode == 0, r.stderr
        keys.append(r.stdout.strip())
    assert keys[0] == kernels.key() and len(set(keys)) == 3 and all(len(k) == 20 for k in keys)


@pytest.mark.slow
def test_the_build_replaces_only_its_own_files(built, tmp_path):
    """``build --force`` writes the file for this key and removes another key's extension (a name it writes), and
    nothing else of the folder; without --force a build finds it there and compiles nothing."""
    where = tmp_path / "k"
    where.mkdir()
    stale = where / f"{kernels.PREFIX}{'1' * 20}{kernels.SUFFIX}"
    stale.write_bytes(b"an extension built for another key")
    mine = where / "notes.txt"
    mine.write_text("kept")
    r = _run(["-m", "platform_tools.dataset.kernels", "build", "--dir", str(where), "--force"], None)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("kernels: built: ")
    assert sorted(p.name for p in where.iterdir()) == sorted([next(built.iterdir()).name, "notes.txt"])
    assert mine.read_text() == "kept"
    r = _run(["-m", "platform_tools.dataset.kernels", "build", "--dir", str(where), "--json"], None)
    assert r.returncode == 0 and json.loads(r.stdout)["built"] is False


def test_a_build_that_cannot_write_fails_with_one_line_naming_the_folder(tmp_path):
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    r = _run(["-m", "platform_tools.dataset.kernels", "build", "--dir", str(blocked)], None)
    assert r.returncode == kernels.EXIT_FAILED
    assert len(r.stderr.strip().splitlines()) == 1 and str(blocked) in r.stderr and "Traceback" not in r.stderr
    assert blocked.read_text() == "not a folder"
    r = _run(["-m", "platform_tools.dataset.kernels", "build", "--dir", str(blocked), "--json"], None)
    assert r.returncode == kernels.EXIT_FAILED and json.loads(r.stdout)["ok"] is False


def test_help_names_the_exit_codes_and_bad_usage_exits_2():
    r = _run(["-m", "platform_tools.dataset.kernels", "--help"], None)
    assert r.returncode == 0 and "exit codes: 0" in r.stdout and "1 the build failed" in r.stdout
    r = _run(["-m", "platform_tools.dataset.kernels", "rebuild"], None)
    assert r.returncode == kernels.EXIT_USAGE and "invalid choice" in r.stderr


class _Recorder:
    def __init__(self):
        self.calls = []

    def __call__(self, *args):
        self.calls.append(args)
        return "extension"


def _checked(name: str):
    fallback_calls = []

    def fallback():
        def jit(*args):
            fallback_calls.append(args)
            return "jit"
        return jit
    rec = _Recorder()
    return kernels.Checked(rec, kernels.KERNELS[name], fallback), rec, fallback_calls


def _blend_args(**change):
    """Arguments of the kind blend_rows takes (register_kernels._blend_rows), by name, some replaced."""
    args = dict(uvz=np.zeros((4, 3)), idx=np.zeros(4, np.int64), src=np.zeros((4, 3), np.uint8), out_h=4, out_w=5,
                tol=0.02, zbuf=np.zeros((4, 5)), row_start=np.zeros(3, np.int64), final_below=np.zeros(2, np.int64),
                packed=np.zeros((4, 5, 5)), finish=1, min_weight=0.5, image=np.zeros((4, 5, 3), np.uint8),
                mask=np.zeros((4, 5), np.uint8), depth_mm=np.zeros((4, 5), np.uint16))
    return tuple((args | change).values())


def _read_only(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@pytest.mark.parametrize("change,where", [
    ({}, "extension"),
    ({"min_weight": 1}, "extension"),                                   # an int where a float is taken
    ({"min_weight": np.float32(0.5)}, "extension"),
    ({"zbuf": _read_only(np.zeros((4, 5)))}, "extension"),              # read, not written: read-only is fine
    ({"packed": np.zeros((4, 5, 5), np.float32)}, "jit"),               # another dtype
    ({"src": np.zeros((4, 3), np.uint16)}, "jit"),
    ({"packed": np.zeros((4, 5, 5), ">f8")}, "jit"),                    # another byte order
    ({"packed": np.zeros((4, 5))}, "jit"),                              # other dimensions
    ({"packed": np.zeros((4, 5, 10))[..., ::2]}, "jit"),                # not C-contiguous
    ({"image": _read_only(np.zeros((4, 5, 3), np.uint8))}, "jit"),      # written but read-only
    ({"min_weight": True}, "jit"),
    ({"min_weight": "0.5"}, "jit"),
    ({"mask": np.zeros((4, 5), np.uint8).view(np.recarray)}, "jit"),    # an ndarray subclass
])
def test_checked_sends_the_extension_only_the_signatures_arguments(change, where):
    """The extension's functions read memory as their signature says (a float32 array read as float64 crashes the
    process); Checked calls them only with exactly those arguments and sends any other call to the JIT."""
    checked, rec, jit_calls = _checked("blend_rows")
    args = _blend_args(**change)
    assert checked(*args) == where
    assert (len(rec.calls), len(jit_calls)) == ((1, 0) if where == "extension" else (0, 1))
    assert (rec.calls or jit_calls)[0] is not None


@pytest.mark.parametrize("value,where", [(7, "extension"), (np.int64(-3), "extension"), (np.uint16(9), "extension"),
                                         (2**63, "jit"), (7.0, "jit"), (False, "jit")])
def test_checked_takes_integers_in_int64s_range_for_integers(value, where):
    checked, rec, jit_calls = _checked("apply_lut")
    args = (np.zeros(4, np.uint16), np.zeros(2, np.uint8), value, 1, np.zeros(4, np.uint8))
    assert checked(*args) == where


def test_checked_sends_a_call_with_another_count_of_arguments_to_the_jit():
    checked, rec, jit_calls = _checked("blend_rows")
    assert checked(*_blend_args()[:-1]) == "jit" and not rec.calls


def test_every_kernel_names_a_function_of_its_module_and_a_signature_numba_can_read():
    """The table the build and the checks read: each kernel's function exists (a numba dispatcher, or a plain function
    the JIT wraps), takes as many arguments as its signature lists, and every written position is an array."""
    import importlib
    import inspect
    for name, k in kernels.KERNELS.items():
        fn = getattr(importlib.import_module(k.module), k.name)
        fn = getattr(fn, "py_func", fn)
        assert len(inspect.signature(fn).parameters) == len(k.args), name
        assert all(kernels._parse(k.args[i])[1] > 0 for i in k.writes), name
        assert k.result in ("void", "i8") and k.signature().startswith(k.result + "(")
