"""Dimensioned drawings of the parts a lab makes: every printed part and the machined heat sink, one
SVG each, generated from the model for a machinist or a print service.

Each drawing has three orthographic views of the part in its own frame (third-angle: plan on top,
elevation under it, side view to the right of the elevation), drawn from OpenCascade's hidden-line
removal of the solid at one known scale; overall dimensions on every view with the general tolerance
(``printing.printer.tolerance_mm`` for printed parts, ``enclosure.heat_sink.tolerance_mm`` for the
machined one); a hole table; for the heat sink the bore (the Boson body plus ``bore_clearance_mm``,
the thermal contact), the fins and the base; and a title block (part, material, rig hash, units,
projection).

Holes (:func:`holes`, cad/drawing_holes.py): every hole the joints cut (and the cable gland's), matched to the cylindrical
face of the solid with its diameter whose axis runs through it, plus every other full-circle
cylindrical cavity of the solid (a lens bore, a handle's access hole, a window, a panel part's
cut-out). Each gets an id (a letter per kind: diameter, depth, purpose; numbered by position) drawn
beside a marker on the view that sees it end-on, and a row: its ordinates in mm from that view's
lower-left corner (the datum: the part's lowest coordinates on the two axes of the view), the face it
is drilled from, diameter, depth, position tolerance (the stack-up's "printed/machined hole position"
term, cad/datums.py) and what it is for, from the joint's role for it (insert, tap drill, pilot,
clearance at the screw fit, a head's counterbore or access hole) or the part's spec; otherwise "hole".
A hole the layout lists but the solid does not have is written where the layout puts it and says so.
On the heat sink the two tapped holes the thermal bar's screws go into get their spacing dimensioned
with the stack-up's tolerance (it sets the camera's yaw) and the bore is placed from their midpoint.

Every dimension is a ``<text class="dim">`` with its value in ``data-value`` (mm) and the axis it
measures in ``data-dim``, every hole a ``<text class="hole-pos">`` with ``data-id``, ``data-hole-view``,
``data-at`` (mm), ``data-diameter``, ``data-depth``, ``data-tolerance`` and ``data-for``, so a test (or
a script) reads the numbers back and compares them with the model's measured sizes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import cadquery as cq
from OCP.BRepLib import BRepLib
from OCP.GCPnts import GCPnts_QuasiUniformDeflection
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.HLRAlgo import HLRAlgo_Projector
from OCP.HLRBRep import HLRBRep_Algo, HLRBRep_HLRToShape

from .assembly import Assembly, Node
from .drawing_holes import HoleMark, _extra_rows, _hole_groups, hole_spacing, holes
from .solids import bounds_of

#: the sheet (px); the views are fitted into it at one scale
SHEET_W, SHEET_H = 1400.0, 1000.0
MARGIN, GAP, TABLE_W = 60.0, 90.0, 470.0
#: how far a dimension line stands off the view (px)
DIM_OFFSET = 28.0
#: the curve discretisation of projected edges (mm)
DEFLECTION_MM = 0.05
#: views: name -> (view direction towards the viewer, paper x direction), all in the part's frame
VIEWS = {
    "plan": ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),          # paper (x, y)
    "elevation": ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),    # paper (x, z)
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),          # paper (y, z)
}
AXES = {"plan": ("x", "y"), "elevation": ("x", "z"), "side": ("y", "z")}


@dataclass(frozen=True)
class Projection:
    visible: list[list[tuple[float, float]]]   # polylines, mm on the paper
    hidden: list[list[tuple[float, float]]]
    lo: tuple[float, float]
    hi: tuple[float, float]


def project(shape: cq.Shape, direction, xdir) -> Projection:
    """Hidden-line projection of ``shape`` on the plane normal to ``direction``, paper x along ``xdir``."""
    hlr = HLRBRep_Algo()
    hlr.Add(shape.wrapped)
    hlr.Projector(HLRAlgo_Projector(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(*direction), gp_Dir(*xdir))))
    hlr.Update()
    hlr.Hide()
    out = HLRBRep_HLRToShape(hlr)

    def lines(compounds) -> list[list[tuple[float, float]]]:
        res = []
        for c in compounds:
            if c.IsNull():
                continue
            BRepLib.BuildCurves3d_s(c, 1e-4)
            for e in cq.Shape(c).Edges():
                curve = e._geomAdaptor()
                pts = GCPnts_QuasiUniformDeflection(curve, DEFLECTION_MM, curve.FirstParameter(), curve.LastParameter())
                if pts.IsDone() and pts.NbPoints() > 1:
                    res.append([(pts.Value(i + 1).X(), pts.Value(i + 1).Y()) for i in range(pts.NbPoints())])
        return res

    vis = lines([out.VCompound(), out.Rg1LineVCompound(), out.OutLineVCompound()])
    hid = lines([out.HCompound(), out.OutLineHCompound()])
    xs = [p[0] for ln in vis + hid for p in ln]
    ys = [p[1] for ln in vis + hid for p in ln]
    return Projection(vis, hid, (min(xs), min(ys)), (max(xs), max(ys)))


@dataclass(frozen=True)
class Drawing:
    part_id: str
    svg: str
    dims: dict[str, float]        # the overall sizes written on it (mm), by axis


def _tolerance(asm: Assembly, node: Node) -> float:
    d = asm.rig.desc
    return d.enclosure.heat_sink.tolerance_mm if node.category == "machined" else d.printing.printer.tolerance_mm


WRAP_CHARS = 76


def _wrap(text: str, width: int) -> list[str]:
    out, line = [], ""
    for word in text.split(" "):
        if line and len(line) + 1 + len(word) > width:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return out + [line]


def _fmt(v: float) -> str:
    return f"{v:.2f}"


def drawing(asm: Assembly, node: Node) -> Drawing:
    """The dimensioned drawing of ``node``'s part (in its own frame)."""
    shape = node.local_shape(asm.cache)
    bb = bounds_of(shape)
    size = dict(zip("xyz", bb.size))
    tol = _tolerance(asm, node)
    proj = {v: project(shape, d, x) for v, (d, x) in VIEWS.items()}
    # the holes, their ordinates from each view's lower-left corner (the drawn outline's: the datum)
    marks = holes(asm, node, lo={v: p.lo for v, p in proj.items()})
    pair = hole_spacing(asm, node, marks)
    # one scale: plan over elevation (width x), side beside the elevation (width y); heights y and z
    w = size["x"] + size["y"]
    h = size["y"] + size["z"]
    s = min((SHEET_W - 2 * MARGIN - GAP - TABLE_W) / w, (SHEET_H - 2 * MARGIN - GAP - 60) / h)
    origin = {"plan": (MARGIN, MARGIN), "elevation": (MARGIN, MARGIN + size["y"] * s + GAP),
              "side": (MARGIN + size["x"] * s + GAP, MARGIN + size["y"] * s + GAP)}
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{SHEET_W:g}" height="{SHEET_H:g}" '
           f'viewBox="0 0 {SHEET_W:g} {SHEET_H:g}" data-part="{node.part_id}" data-scale-px-per-mm="{s:.6f}">',
           '<style>.v{fill:none;stroke:#000;stroke-width:1}.h{fill:none;stroke:#999;stroke-width:0.6;'
           'stroke-dasharray:4 3}.d{stroke:#1f4e9c;stroke-width:0.7}text{font-family:sans-serif;font-size:13px}'
           '.dim{fill:#1f4e9c}.hm{fill:none;stroke:#c0392b;stroke-width:0.8}'
           '.hole-id{font-size:10px;fill:#c0392b;paint-order:stroke;stroke:#fff;stroke-width:3px;stroke-linejoin:round}'
           '.datum{fill:#1f4e9c;font-size:10px}.pos{font-size:10px}.pos-head{font-size:10px;font-weight:bold}</style>',
           f'<rect x="1" y="1" width="{SHEET_W - 2:g}" height="{SHEET_H - 2:g}" fill="#fff" stroke="#000"/>']
    for view, p in proj.items():
        ox, oy = origin[view]
        ax, ay = AXES[view]
        vh = (p.hi[1] - p.lo[1]) * s

        def tx(pt, p=p, ox=ox, oy=oy, vh=vh):     # paper mm -> sheet px (y up on paper, down on the sheet)
            return ox + (pt[0] - p.lo[0]) * s, oy + vh - (pt[1] - p.lo[1]) * s

        out.append(f'<g class="view" id="view-{view}" data-width-mm="{p.hi[0] - p.lo[0]:.4f}" '
                   f'data-height-mm="{p.hi[1] - p.lo[1]:.4f}">')
        for cls, lines in (("h", p.hidden), ("v", p.visible)):
            for ln in lines:
                pts = " ".join(f"{a:.2f},{b:.2f}" for a, b in map(tx, ln))
                out.append(f'<polyline class="{cls}" points="{pts}"/>')
        out.append(f'<text x="{ox:g}" y="{oy - 8:g}">{view} ({ax}, {ay})</text>')
        # overall dimensions: the width under the view, the height to its left
        wmm, hmm = p.hi[0] - p.lo[0], p.hi[1] - p.lo[1]
        y_d = oy + vh + DIM_OFFSET
        out.append(f'<line class="d" x1="{ox:.2f}" y1="{y_d:.2f}" x2="{ox + wmm * s:.2f}" y2="{y_d:.2f}"/>')
        out.append(f'<text class="dim" data-view="{view}" data-dim="{ax}" data-value="{wmm:.3f}" '
                   f'x="{ox + wmm * s / 2:.2f}" y="{y_d - 4:.2f}" text-anchor="middle">{wmm:.1f} ±{tol:g}</text>')
        x_d = ox - DIM_OFFSET
        out.append(f'<line class="d" x1="{x_d:.2f}" y1="{oy:.2f}" x2="{x_d:.2f}" y2="{oy + vh:.2f}"/>')
        out.append(f'<text class="dim" data-view="{view}" data-dim="{ay}" data-value="{hmm:.3f}" '
                   f'x="{x_d - 4:.2f}" y="{oy + vh / 2:.2f}" text-anchor="middle" '
                   f'transform="rotate(-90 {x_d - 4:.2f} {oy + vh / 2:.2f})">{hmm:.1f} ±{tol:g}</text>')
        out.append("</g>")
        mine = [m for m in marks if m.view == view]
        if not mine:
            continue
        # the datum: the view's lower-left corner, every hole's ordinates run from it
        out.append(f'<g class="holes" id="holes-{view}">')
        out.append(f'<path class="d" d="M{ox:.2f},{oy + vh + 6:.2f} L{ox:.2f},{oy + vh:.2f} L{ox - 6:.2f},{oy + vh:.2f}"/>')
        out.append(f'<text class="datum" x="{ox + 3:.2f}" y="{oy + vh + 12:.2f}">0,0 ({ax}, {ay})</text>')
        at: dict[tuple[int, int], list[str]] = {}
        for m in mine:
            cx, cy = tx((p.lo[0] + m.at[0], p.lo[1] + m.at[1]))
            r = max(m.diameter / 2 * s, 2.0)
            out.append(f'<circle class="hm" data-hole="{m.id}" cx="{cx:.2f}" cy="{cy:.2f}" r="{r:.2f}"/>')
            out.append(f'<path class="hm" d="M{cx - r - 2:.2f},{cy:.2f} H{cx + r + 2:.2f} M{cx:.2f},{cy - r - 2:.2f} '
                       f'V{cy + r + 2:.2f}"/>')
            at.setdefault((round(cx), round(cy)), []).append(m.id)
        for (cx, cy), ids in at.items():
            r = max(max(m.diameter for m in mine if m.id in ids) / 2 * s, 2.0)
            out.append(f'<text class="hole-id" data-ids="{" ".join(ids)}" x="{cx + 0.7 * r + 2:.1f}" '
                       f'y="{cy - 0.7 * r - 2:.1f}">{"/".join(ids)}</text>')
        if pair is not None and pair[0].view == view:
            out.append(_spacing_dim(pair, tx, p, ox, oy, wmm * s, vh))
        out.append("</g>")
    # the table: title block, critical features, holes (kinds, then each hole's position)
    tx0, ty = SHEET_W - MARGIN - TABLE_W + 20, MARGIN
    material = asm.rig.desc.enclosure.heat_sink.material if node.category == "machined" else asm.rig.desc.printing.printer.material
    rows = [f"<tspan font-weight='bold'>{escape(node.part_id)}</tspan>", f"{node.category}, {escape(material)}",
            f"units mm; general tolerance ±{tol:g}", "third-angle projection", f"rig {asm.rig.hash[:12]}",
            f"quantity per rig {len(asm.by_part(node.part_id))}"]
    for r in rows:
        out.append(f'<text x="{tx0:g}" y="{ty:g}">{r}</text>')
        ty += 20
    extra = _extra_rows(asm, node, pair, bb.lo[2])
    if extra:
        ty += 10
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">critical features</text>')
        for k, (label, v, t) in enumerate(extra):
            ty += 17
            out.append(f'<text class="dim" data-dim="feature-{k}" data-label="{escape(label)}" data-value="{v:.3f}" '
                       f'x="{tx0:g}" y="{ty:g}" font-size="11">{escape(label)}: {_fmt(v)} {escape(t)}</text>')
    if marks:
        ty += 26
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">holes</text>')
        for r in _hole_groups(marks):
            lines = _wrap(r, WRAP_CHARS)
            ty += 15
            spans = "".join(f'<tspan x="{tx0 + (12 if k else 0):g}" dy="{13 if k else 0}">{escape(ln)}</tspan>'
                            for k, ln in enumerate(lines))
            out.append(f'<text class="hole" x="{tx0:g}" y="{ty:g}" font-size="10">{spans}</text>')
            ty += 13 * (len(lines) - 1)
        # one row a hole: id, the view and face, its ordinates from the view's datum corner, size, tolerance, use
        step = min(13.0, (SHEET_H - 20 - ty - 40) / (len(marks) + 1))
        ty += 20
        out.append(f'<text class="pos" x="{tx0:g}" y="{ty:g}">positions: mm from each view\'s datum corner (0,0: '
                   f'the part\'s lowest x, y, z)</text>')
        ty += step + 2
        out.append(_pos_row(tx0, ty, ("id", "view", "from", "at", "", "Ø", "depth", "pos.", "for"), head=True))
        for m in marks:
            ty += step
            a1, a2 = AXES[m.view]
            cells = (m.id, m.view, m.face or "-", f"{a1} {_fmt(m.at[0])}", f"{a2} {_fmt(m.at[1])}", f"{m.diameter:.2f}",
                     f"{m.depth:.1f}", f"±{m.tolerance:g}", m.purpose + ("" if m.on_solid else " (layout; not on the solid)"))
            attrs = (f'data-id="{m.id}" data-hole-view="{m.view}" data-axes="{a1}{a2}" '
                     f'data-at="{m.at[0]:.4f} {m.at[1]:.4f}" data-centre="{" ".join(f"{v:.4f}" for v in m.centre)}" '
                     f'data-diameter="{m.diameter:.4f}" data-depth="{m.depth:.4f}" data-tolerance="{m.tolerance:g}" '
                     f'data-face="{m.face}" data-for="{escape(m.purpose)}" data-on-solid="{int(m.on_solid)}"')
            out.append(_pos_row(tx0, ty, cells, attrs=attrs, size=min(10.0, step - 1)))
    out.append("</svg>")
    return Drawing(node.part_id, "\n".join(out) + "\n", {k: round(v, 3) for k, v in size.items()})


#: the position table's columns (px from the table's left edge)
POS_COLUMNS = (0, 30, 88, 120, 182, 244, 286, 320, 356)


def _pos_row(x0: float, y: float, cells, *, head: bool = False, attrs: str = "", size: float = 10.0) -> str:
    spans = "".join(f'<tspan x="{x0 + c:g}">{escape(str(v))}</tspan>' for c, v in zip(POS_COLUMNS, cells))
    cls = "pos-head" if head else "hole-pos"
    return f'<text class="{cls}" {attrs} y="{y:.1f}" font-size="{size:.1f}">{spans}</text>'


def _spacing_dim(pair: tuple[HoleMark, HoleMark], tx, p: Projection, ox: float, oy: float, w_px: float, h_px: float) -> str:
    """The two tapped holes' spacing as a dimension beside the view, with its tolerance (a ``dim`` text)."""
    a, b = (tx((p.lo[0] + m.at[0], p.lo[1] + m.at[1])) for m in pair)
    d = math.hypot(pair[0].at[0] - pair[1].at[0], pair[0].at[1] - pair[1].at[1])
    label = f"{d:.2f} ±{pair[0].tolerance:g} ({pair[0].id}-{pair[1].id})"
    attrs = (f'class="dim" data-dim="hole-spacing" data-holes="{pair[0].id} {pair[1].id}" data-value="{d:.4f}" '
             f'data-tolerance="{pair[0].tolerance:g}"')
    parts = []
    if abs(a[1] - b[1]) >= abs(a[0] - b[0]):       # apart on the sheet's vertical: dimension to the right
        xd = ox + w_px + 18
        for x, y in (a, b):
            parts.append(f'<line class="d" x1="{x:.2f}" y1="{y:.2f}" x2="{xd + 4:.2f}" y2="{y:.2f}"/>')
        parts.append(f'<line class="d" x1="{xd:.2f}" y1="{a[1]:.2f}" x2="{xd:.2f}" y2="{b[1]:.2f}"/>')
        ym = (a[1] + b[1]) / 2
        parts.append(f'<text {attrs} x="{xd + 14:.2f}" y="{ym:.2f}" text-anchor="middle" '
                     f'transform="rotate(-90 {xd + 14:.2f} {ym:.2f})">{label}</text>')
    else:                                            # apart across: dimension above the view
        yd = oy - 22
        for x, y in (a, b):
            parts.append(f'<line class="d" x1="{x:.2f}" y1="{y:.2f}" x2="{x:.2f}" y2="{yd - 4:.2f}"/>')
        parts.append(f'<line class="d" x1="{a[0]:.2f}" y1="{yd:.2f}" x2="{b[0]:.2f}" y2="{yd:.2f}"/>')
        parts.append(f'<text {attrs} x="{(a[0] + b[0]) / 2:.2f}" y="{yd - 4:.2f}" text-anchor="middle">{label}</text>')
    return "\n".join(parts)


def write_drawings(asm: Assembly, folder: Path) -> list[Path]:
    """``<part>.drawing.svg`` for every printed and machined part, into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for pid, n in asm.printed().items():
        p = folder / f"{pid}.drawing.svg"
        p.write_text(drawing(asm, n).svg)
        out.append(p)
    return out


def scale_of(svg_text: str) -> float:
    import re
    m = re.search(r'data-scale-px-per-mm="([0-9.]+)"', svg_text)
    return float(m.group(1)) if m else math.nan
