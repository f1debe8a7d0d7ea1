"""What `python cad/build.py export` writes and what it may replace: its formats, the marker file that lists
the files an export wrote, and what in a folder no export wrote (which ``--out`` never deletes).

Files and names only, no CadQuery: ``export`` refuses a bad format or an ``--out`` folder holding someone's files
before it loads the B-rep kernel (cad/export.py writes the shapes).
"""
from __future__ import annotations

import json
import os
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .assembly import Assembly

FORMATS = ("STEP", "STL", "GLB", "SVG", "PNG")
#: every export writes this file: its manifest (JSON: the files it wrote, relative to the folder). A
#: folder holding it is a previous export, which ``--out`` may replace only while it holds nothing else
EXPORT_MARKER = ".rig-cad-export"
#: what an export writes (relative paths, glob patterns): what an older export, whose marker is one line
#: of text and lists nothing, or a folder without a marker may hold and still be replaced
EXPORT_PATTERNS = ("rig_assembly.step", "rig_assembly.glb", "assembly_tree.json", "camera_frames.json",
                   "printed/*.step", "printed/*.stl", "printed/*.drawing.svg", "views/*.svg", "views/*.png",
                   EXPORT_MARKER)


def written_files(folder: Path) -> set[str] | None:
    """The files (relative POSIX paths) the export that left ``folder`` recorded in its manifest; None
    when it recorded none (no marker, or an older export's one-line marker)."""
    try:
        doc = json.loads((Path(folder) / EXPORT_MARKER).read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    files = doc.get("files") if isinstance(doc, dict) else None
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        return None
    return set(files) | {EXPORT_MARKER}


def foreign_files(folder: Path) -> list[Path]:
    """What in ``folder`` no export wrote: files and folders that replacing the folder would delete.
    Empty when the folder does not exist or holds only what the previous export recorded in its
    manifest (without a manifest: only names an export writes, :data:`EXPORT_PATTERNS`). A foreign
    folder is listed once, not its contents; the list is sorted, shallowest first."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    manifest = written_files(folder)
    if manifest is not None:
        def ours(rel: str) -> bool:
            return rel in manifest
        dirs = {"/".join(f.split("/")[:i]) for f in manifest for i in range(1, f.count("/") + 1)}
    else:
        def ours(rel: str) -> bool:
            path = PurePosixPath(rel)     # a pattern matches from the right: compare whole paths
            return any(len(path.parts) == pat.count("/") + 1 and path.match(pat) for pat in EXPORT_PATTERNS)
        dirs = {pat.rsplit("/", 1)[0] for pat in EXPORT_PATTERNS if "/" in pat}
    out = []
    for root, subdirs, files in os.walk(folder):   # does not follow links: a link is an entry like a file
        here = Path(root)
        for d in list(subdirs):
            rel = (here / d).relative_to(folder).as_posix()
            if (here / d).is_symlink() or rel not in dirs:
                out.append(here / d)
                subdirs.remove(d)
        out += [here / f for f in files if not ours((here / f).relative_to(folder).as_posix())]
    return sorted(out, key=lambda p: (len(p.relative_to(folder).parts), str(p)))


def write_manifest(asm: Assembly, stage: Path) -> Path:
    """The marker, listing every file now in ``stage``: what this export wrote, and all the next
    export may delete."""
    files = sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file() and p.name != EXPORT_MARKER)
    marker = stage / EXPORT_MARKER
    marker.write_text(json.dumps({"written_by": "cad/build.py export", "rig_hash": asm.rig.hash, "files": files},
                                 indent=1) + "\n")
    return marker
