"""The house rules of this repository's layout, as functions over an import graph (tests/test_layout.py applies
them to the project and proves each one fails on a deliberate violation).

The floor plan: every project module belongs to a *room* (a package prefix) on a *floor*. A module may import
modules of its own room and of rooms on strictly lower floors; nothing else of ours. Imports inside functions
count as much as those at the top of a file.

    floor 0  platform_tools.rig            the rig description: schema, loader, frames, units, atomic outputs,
                                           the one problem type, progress, command conventions, nominal cameras
    floor 1  platform_tools.boson          FLIR Boson protocol, client, sync set-up, telemetry wire format, emulator
             cad                           the parametric CAD model, its checks and exports
             calibration                   synthetic images, detection, intrinsics, formats, report
    floor 2  calibration.extrinsics        extrinsics, from the CAD model and from images
             bom                           the bill of materials, from the CAD assembly
             firmware                      the on-device configuration (renderer + templates) and runtime
    floor 3  calibration.rigsynth          synchronised synthetic rig images (uses the extrinsics)
             docs.guide                    the assembly guide site (steps, pictures, wiring), from CAD and BOM
             platform_tools.dataset        recordings -> a dataset
             platform_tools.sim            the simulated rig (recordings with known faults)
    floor 4  commands (parse, call, print)
             platform_tools.cli            the `platform_tools` tool and its subcommands
             calibration.commands          the `calibrate` subcommands
    floor 5  what gathers commands into a tool
             calibration.cli               `calibrate`
             cad.build                     `python cad/build.py` (CAD, BOM and guide commands)
             platform_tools.demo           `make demo`

Besides the floors:
- no import cycle between files;
- no cycle between sibling sub-folders of one package (a package's own root files are not part of this rule);
- no non-test module longer than :data:`MAX_LINES` lines;
- device-only libraries (ROS 2, GPIO) are imported only in the on-device package;
- what the device images install (the on-device package and the packages it needs) is closed under imports.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping

#: the project's top-level Python packages
PACKAGES = ("platform_tools", "calibration", "cad", "bom", "firmware", "docs")

#: room (a dotted package prefix) -> floor; the longest matching prefix decides a module's room
FLOORS: dict[str, int] = {
    "platform_tools.rig": 0,
    "platform_tools.boson": 1,
    "cad": 1,
    "calibration": 1,
    "calibration.extrinsics": 2,
    "bom": 2,
    "firmware": 2,
    "calibration.rigsynth": 3,
    "docs": 3,
    "platform_tools.dataset": 3,
    "platform_tools.sim": 3,
    "platform_tools.cli": 4,
    "calibration.commands": 4,
    "calibration.cli": 5,
    "cad.build": 5,
    "platform_tools.demo": 5,
}
#: package roots that hold nothing but sub-packages (their __init__ imports nothing), so need no floor of their own
NAMESPACE_ROOTS = ("platform_tools",)

MAX_LINES = 600

#: third-party modules that exist only on the device (ROS 2 client library and messages, the Jetson's GPIO)
DEVICE_ONLY_IMPORTS = ("rclpy", "launch", "launch_ros", "sensor_msgs", "diagnostic_msgs", "std_msgs",
                       "Jetson", "RPi", "gpiod")
#: the on-device package: where device-only imports may appear, and what the device images install
DEVICE_PACKAGE = "firmware"
#: what the device images install besides DEVICE_PACKAGE
DEVICE_INSTALL = ("firmware", "platform_tools.rig", "platform_tools.boson")


@dataclass(frozen=True)
class Module:
    name: str                  # dotted, e.g. platform_tools.rig.loader (a package is its __init__)
    path: Path
    is_package: bool
    lines: int
    imports: frozenset[str] = frozenset()     # project modules it imports
    external: frozenset[str] = frozenset()    # top-level names of the other modules it imports


def _dotted(root: Path, path: Path) -> tuple[str, bool]:
    parts = list(path.relative_to(root).with_suffix("").parts)
    is_package = parts[-1] == "__init__"
    if is_package:
        parts = parts[:-1]
    return ".".join(parts), is_package


def _imported_names(module: str, is_package: bool, tree: ast.AST) -> Iterable[tuple[str, tuple[str, ...]]]:
    """(absolute module, names imported from it) for every import statement anywhere in ``tree``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".") if is_package else module.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            yield name, tuple(a.name for a in node.names)


def scan(root: Path, packages: Iterable[str] = PACKAGES) -> dict[str, Module]:
    """Every module of ``packages`` under ``root`` with the project modules it imports (the most specific module
    an import names: ``from a.b import c`` is ``a.b.c`` when that is a module, else ``a.b``)."""
    files = {}
    for pkg in packages:
        base = root / pkg
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            name, is_package = _dotted(root, path)
            files[name] = (path, is_package)
    modules = {}
    for name, (path, is_package) in files.items():
        text = path.read_text()
        tree = ast.parse(text, filename=str(path))
        ours, external = set(), set()
        for target, names in _imported_names(name, is_package, tree):
            candidates = [f"{target}.{n}" for n in names if f"{target}.{n}" in files] or [target]
            for cand in candidates:
                parts = cand.split(".")
                for i in range(len(parts), 0, -1):
                    prefix = ".".join(parts[:i])
                    if prefix in files:
                        if prefix != name:
                            ours.add(prefix)
                        break
                else:
                    if parts[0] not in packages:
                        external.add(parts[0])
        modules[name] = Module(name, path, is_package, text.count("\n") + 1, frozenset(ours), frozenset(external))
    return modules


def room_of(module: str, floors: Mapping[str, int] = FLOORS) -> str | None:
    best = None
    for room in floors:
        if (module == room or module.startswith(room + ".")) and (best is None or len(room) > len(best)):
            best = room
    return best


def unassigned(modules: Mapping[str, Module], floors: Mapping[str, int] = FLOORS,
               namespace_roots: Iterable[str] = NAMESPACE_ROOTS) -> list[str]:
    """Modules no room holds (a new top-level module or package nobody placed on the plan)."""
    return sorted(m for m in modules if room_of(m, floors) is None and m not in set(namespace_roots))


def floor_violations(modules: Mapping[str, Module], floors: Mapping[str, int] = FLOORS) -> list[str]:
    """Every import that goes sideways or up: to another room on the same or a higher floor."""
    out = []
    for m in sorted(modules):
        src = room_of(m, floors)
        if src is None:
            continue
        for target in sorted(modules[m].imports):
            dst = room_of(target, floors)
            if dst is None or dst == src:
                continue
            if floors[dst] >= floors[src]:
                how = "sideways" if floors[dst] == floors[src] else "up"
                out.append(f"{m} (floor {floors[src]}, {src}) imports {target} (floor {floors[dst]}, {dst}): {how}")
    return out


def _cycles(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan), each sorted; sorted list."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v: str) -> None:
        work = [(v, iter(sorted(graph.get(v, ()))))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        while work:
            node, it = work[-1]
            for w in it:
                if w not in graph:
                    continue
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def file_cycles(modules: Mapping[str, Module]) -> list[list[str]]:
    """Groups of modules that import each other, directly or round a loop."""
    return _cycles({m: mod.imports for m, mod in modules.items()})


def folder_cycles(modules: Mapping[str, Module]) -> list[list[str]]:
    """Loops between sibling sub-folders: a module in ``p.a`` importing one in ``p.b`` is an edge ``p.a -> p.b``
    for every package ``p`` with sub-packages ``a`` and ``b``."""
    packages = {m for m, mod in modules.items() if mod.is_package}
    graph: dict[str, set[str]] = {p: set() for p in packages}
    for m, mod in modules.items():
        for target in mod.imports:
            a, b = m.split("."), target.split(".")
            common = 0
            while common < min(len(a), len(b)) and a[common] == b[common]:
                common += 1
            if common == 0 or common >= len(a) or common >= len(b):
                continue
            sa, sb = ".".join(a[:common + 1]), ".".join(b[:common + 1])
            if sa in packages and sb in packages and sa != sb:
                graph[sa].add(sb)
    return _cycles(graph)


def long_modules(modules: Mapping[str, Module], max_lines: int = MAX_LINES) -> list[str]:
    return [f"{m}: {mod.lines} lines (at most {max_lines})" for m, mod in sorted(modules.items())
            if mod.lines > max_lines]


def device_imports_outside(modules: Mapping[str, Module], package: str = DEVICE_PACKAGE,
                           device_only: Iterable[str] = DEVICE_ONLY_IMPORTS) -> list[str]:
    """Modules outside the on-device package that import a device-only library (on-device runtime code)."""
    device_only = set(device_only)
    return [f"{m} imports {', '.join(sorted(mod.external & device_only))}" for m, mod in sorted(modules.items())
            if not (m == package or m.startswith(package + ".")) and mod.external & device_only]


def install_set_leaks(modules: Mapping[str, Module], install: Iterable[str] = DEVICE_INSTALL,
                      package: str = DEVICE_PACKAGE) -> list[str]:
    """Imports, reached from the on-device package, of modules the device images do not install."""
    install = tuple(install)

    def installed(m: str) -> bool:
        return any(m == p or m.startswith(p + ".") for p in install) or any(p.startswith(m + ".") for p in install)

    seen, todo, out = set(), [m for m in modules if m == package or m.startswith(package + ".")], []
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        for target in sorted(modules[m].imports):
            if not installed(target):
                out.append(f"{m} imports {target}, which the device images do not install")
            elif target not in seen:
                todo.append(target)
    return sorted(out)
