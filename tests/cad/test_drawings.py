"""Dimensioned drawings (issue 16): every printed part and the heat sink, read back as SVG; the numbers on
them equal the sizes measured on the part's STEP read back by OpenCascade, and the lines drawn agree
with the numbers at the sheet's scale."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import cadquery as cq
import numpy as np
import pytest

from cad.drawings import VIEWS, drawing, scale_of, write_drawings

pytestmark = pytest.mark.slow
NS = {"s": "http://www.w3.org/2000/svg"}


@pytest.fixture(scope="module")
def drawings(asm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("drawings")
    return folder, write_drawings(asm, folder)


def _dims(root) -> dict[tuple[str, str], float]:
    return {(t.get("data-view"), t.get("data-dim")): float(t.get("data-value"))
            for t in root.iterfind(".//s:text[@class='dim']", NS) if t.get("data-view")}


def test_every_made_part_has_a_drawing(asm, drawings):
    folder, paths = drawings
    assert sorted(p.name for p in paths) == sorted(f"{pid}.drawing.svg" for pid in asm.printed())


def test_dimensions_equal_the_step_read_back(asm, drawings, tmp_path):
    folder, _ = drawings
    for pid, n in asm.printed().items():
        root = ET.parse(folder / f"{pid}.drawing.svg").getroot()
        dims = _dims(root)
        step = tmp_path / f"{pid}.step"
        cq.exporters.export(n.local_shape(asm.cache), str(step), "STEP")
        bb = cq.importers.importStep(str(step)).val().BoundingBox()
        # OCC's box of a re-read STEP may be up to ~0.01 mm loose; the HLR outline is exact
        want = {"x": bb.xlen, "y": bb.ylen, "z": bb.zlen}
        assert {k for _, k in dims} == {"x", "y", "z"}, pid
        for (view, axis), v in dims.items():
            assert v == pytest.approx(want[axis], abs=0.03), (pid, view, axis)
        # the text says the tolerance of the part's process
        tol = asm.rig.desc.enclosure.heat_sink.tolerance_mm if n.category == "machined" else \
            asm.rig.desc.printing.printer.tolerance_mm
        assert all(t.text.endswith(f"±{tol:g}") for t in root.iterfind(".//s:text[@data-view]", NS)), pid


def test_lines_drawn_at_the_sheet_scale(asm, drawings):
    folder, _ = drawings
    for pid in ("case_lid", "heat_sink", "zed_mount"):
        text = (folder / f"{pid}.drawing.svg").read_text()
        s = scale_of(text)
        root = ET.fromstring(text)
        dims = _dims(root)
        for view in VIEWS:
            g = root.find(f".//s:g[@id='view-{view}']", NS)
            pts = np.array([[float(a) for a in p.split(",")] for pl in g.iterfind("s:polyline", NS)
                            for p in pl.get("points").split()])
            width_px, height_px = np.ptp(pts[:, 0]), np.ptp(pts[:, 1])
            ax, ay = {"plan": "xy", "elevation": "xz", "side": "yz"}[view]
            assert width_px / s == pytest.approx(dims[(view, ax)], abs=0.05), (pid, view)
            assert height_px / s == pytest.approx(dims[(view, ay)], abs=0.05), (pid, view)


def test_heat_sink_drawing_gives_the_bore_and_holes(asm, rig, drawings):
    folder, _ = drawings
    root = ET.parse(folder / "heat_sink.drawing.svg").getroot()
    feats = {t.get("data-label"): float(t.get("data-value")) for t in root.iterfind(".//s:text[@data-label]", NS)}
    env = rig.part(rig.desc.sensors.thermal.part).envelope_mm
    assert feats["bore width"] == pytest.approx(env.y.value) and feats["bore height"] == pytest.approx(env.z.value)
    assert feats["fin height"] == rig.desc.enclosure.heat_sink.fin_height_mm
    holes = [t.text for t in root.iterfind(".//s:text[@class='hole']", NS)]
    assert any("tap drill, then tap M3" in h and "2 off" in h for h in holes), holes


def test_case_lower_drawing_lists_the_gland_hole(asm, drawings):
    folder, _ = drawings
    root = ET.parse(folder / "case_lower.drawing.svg").getroot()
    holes = [t.text for t in root.iterfind(".//s:text[@class='hole']", NS)]
    d = asm.layout.power.gland.hole_d_mm
    assert any(h.startswith(f"Ø{d:g} x") and "cable gland" in h for h in holes), holes
