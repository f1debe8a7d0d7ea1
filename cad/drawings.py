"""Dimensioned drawings of the parts a lab makes: every printed part and the machined heat sink, one
SVG each, generated from the model for a machinist or a print service.

Each drawing has three orthographic views of the part in its own frame (third-angle: plan on top,
elevation under it, side view to the right of the elevation), drawn from OpenCascade's hidden-line
removal of the solid at one known scale; overall dimensions on every view with the general tolerance
(``printing.printer.tolerance_mm`` for printed parts, ``enclosure.heat_sink.tolerance_mm`` for the
machined one); a hole table (every hole the joints cut: diameter, depth, count) with the fit it was
sized for; for the heat sink the bore (the Boson body plus ``bore_clearance_mm``, the thermal contact),
the fins and the base; and a title block (part, material, rig hash, units, projection).

Every dimension is a ``<text class="dim">`` with its value in ``data-value`` (mm) and the axis it
measures in ``data-dim``, so a test (or a script) reads the numbers back and compares them with the
model's measured sizes.
"""
from __future__ import annotations

import math
from collections import Counter
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
from .geom import bounds_of

#: the sheet (px); the views are fitted into it at one scale
SHEET_W, SHEET_H = 1400.0, 1000.0
MARGIN, GAP, TABLE_W = 60.0, 90.0, 360.0
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


def _holes(asm: Assembly, node: Node) -> list[str]:
    """The hole table's rows: diameter, depth and count of every hole the joints cut in this part (one
    node of it: every node of a part id gets the same holes), with the fit each diameter was sized for."""
    holes = node.spec.holes if node.category == "machined" else asm.layout.holes_for(node.name)
    case = getattr(node.spec, "spec", None)        # a case half: its spec holds the joints' holes and the gland's
    if case is not None and hasattr(case, "holes"):
        holes = tuple(h for h in case.holes if h.part == node.part_id)
    rows = Counter((round(h.diameter, 2), round(h.depth, 1)) for h in holes)
    fits = asm.layout.fits
    notes = {round(v, 2): f"{t} clearance, {asm.rig.desc.enclosure.screw_fit} fit" for t, v in fits.screw_holes_mm.items()}
    notes[round(fits.insert.hole_diameter_mm, 2)] = f"heat-set insert {asm.rig.part(asm.rig.desc.enclosure.insert).part_number}"
    from cad.bought.fasteners import fastener_table
    for j in asm.layout.joints:   # holes we tap ourselves (the heat sink's copper)
        tap = fastener_table().size(j.thread).tap_drill_mm
        if j.kind == "tapped" and tap is not None:
            notes.setdefault(round(tap, 2), f"tap drill, then tap {j.thread}")
    gland = asm.layout.power.gland
    notes[round(gland.hole_d_mm, 2)] = f"cable gland {asm.rig.part(gland.part_id).part_number}"
    return [f"Ø{d:g} x {depth:g} deep, {n} off" + (f" ({notes[d]})" if d in notes else "")
            for (d, depth), n in sorted(rows.items())]


def _extra_rows(asm: Assembly, node: Node) -> list[tuple[str, float, str]]:
    """Critical features beyond the outline, for the heat sink: (label, value mm as modelled, tolerance text)."""
    if node.category != "machined":
        return []
    hs = asm.rig.desc.enclosure.heat_sink
    spec = node.spec
    b, t = spec.body, f"±{hs.tolerance_mm:g}"
    fit = f"+{hs.bore_clearance_mm:g}/0 (the Boson body; thermal contact faces)"
    rows = [("bore width", b.size[1], fit), ("bore height", b.size[2], fit), ("bore length", b.size[0], t),
            (f"fin thickness ({spec.fins} fins a side)", spec.fin_t, t), ("fin height", spec.fin_h, t),
            ("sleeve wall", spec.wall, t), ("base under the sleeve", spec.base, t)]
    if getattr(spec, "stop", 0) > 0:
        rows += [("front stop thickness (datum face)", spec.stop, t), ("front stop bore (the lens)", spec.stop_bore, t)]
    return rows


def drawing(asm: Assembly, node: Node) -> Drawing:
    """The dimensioned drawing of ``node``'s part (in its own frame)."""
    shape = node.local_shape(asm.cache)
    bb = bounds_of(shape)
    size = dict(zip("xyz", bb.size))
    tol = _tolerance(asm, node)
    proj = {v: project(shape, d, x) for v, (d, x) in VIEWS.items()}
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
           '.dim{fill:#1f4e9c}</style>',
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
    # the table: critical features, holes, title block
    tx0, ty = SHEET_W - MARGIN - TABLE_W + 20, MARGIN
    material = asm.rig.desc.enclosure.heat_sink.material if node.category == "machined" else asm.rig.desc.printing.printer.material
    rows = [f"<tspan font-weight='bold'>{escape(node.part_id)}</tspan>", f"{node.category}, {escape(material)}",
            f"units mm; general tolerance ±{tol:g}", "third-angle projection", f"rig {asm.rig.hash[:12]}",
            f"quantity per rig {len(asm.by_part(node.part_id))}"]
    for r in rows:
        out.append(f'<text x="{tx0:g}" y="{ty:g}">{r}</text>')
        ty += 20
    extra = _extra_rows(asm, node)
    if extra:
        ty += 10
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">critical features</text>')
        for k, (label, v, t) in enumerate(extra):
            ty += 20
            out.append(f'<text class="dim" data-dim="feature-{k}" data-label="{escape(label)}" data-value="{v:.3f}" '
                       f'x="{tx0:g}" y="{ty:g}" font-size="12">{escape(label)}: {v:.2f} {escape(t)}</text>')
    holes = _holes(asm, node)
    if holes:
        ty += 30
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">holes</text>')
        for r in holes[:30]:
            ty += 18
            out.append(f'<text class="hole" x="{tx0:g}" y="{ty:g}" font-size="12">{escape(r)}</text>')
    out.append("</svg>")
    return Drawing(node.part_id, "\n".join(out) + "\n", {k: round(v, 3) for k, v in size.items()})


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
