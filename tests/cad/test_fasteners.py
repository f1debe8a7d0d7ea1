"""The fastener table answers what a joint asks of a thread; joints hold typed fasteners."""
import math

import numpy as np
import pytest

from cad.bought.fasteners import FastenerTableError, Insert, Screw, fastener_table


def test_table_answers_diameter_tap_drill_screw_and_insert():
    t = fastener_table()
    assert t.size("M3").diameter_mm == 3.0 and t.size("1/4-20 UNC").diameter_mm == pytest.approx(25.4 / 4)
    assert t.size("M3").tap_drill_mm < t.size("M3").diameter_mm
    assert t.size("M2.5").screw == "m2p5_screw" and t.thread_of_insert("m3_insert") == "M3"
    with pytest.raises(ValueError, match="unknown thread 'M4'"):
        t.size("M4")


def test_pick_length_is_the_longest_stock_length_in_the_engagement_window():
    t = fastener_table()
    # 4 mm clamped, 2.15..4.7 mm of thread wanted: 8 mm gives 4 mm (10 mm would give 6)
    assert t.pick_length(4.0, 2.15, 4.7) == 8.0
    assert t.pick_length(4.0, 2.15, 4.7) in t.stock_lengths_mm
    with pytest.raises(ValueError, match="no stock screw length"):
        t.pick_length(60.0, 1.0, 2.0)


def test_a_bad_table_is_one_line_naming_file_and_line(tmp_path):
    bad = tmp_path / "fasteners.yaml"
    bad.write_text("stock_lengths_mm: [4, 5]\nsizes:\n  M3:\n    diameter_mm: -3\n    screw: m3_screw\n")
    with pytest.raises(FastenerTableError) as exc:
        fastener_table(bad)
    assert str(bad) + ":4:" in str(exc.value) and "diameter_mm" in str(exc.value)


def test_insert_sizes_come_from_its_rig_part(rig):
    ins = Insert.from_rig(rig, rig.desc.enclosure.insert)
    part = rig.part(rig.desc.enclosure.insert)
    assert (ins.length_mm, ins.outer_diameter_mm) == (part.envelope_mm.x.value, part.envelope_mm.y.value)
    assert ins.hole_diameter_mm == rig.dim(ins.part_id, "hole_diameter_mm") and ins.bore_mm == 3.0


@pytest.mark.slow
def test_joints_hold_fasteners_and_the_bom_counts_them(asm):
    from bom.bom import build_bom
    from bom.catalogue import load_catalogue
    joints = asm.layout.joints
    assert all(isinstance(j.screw, Screw) for j in joints)
    assert all((j.insert is not None) == (j.kind == "insert") for j in joints)
    bom = build_bom(asm, load_catalogue(asm.rig))
    for key in {j.screw.bom_key for j in joints}:
        assert bom.line(key).quantity == sum(j.screw.bom_key == key for j in joints), key
    assert bom.line("m3_insert").quantity == sum(j.insert is not None for j in joints)


def test_standoff_lengths_are_the_shortest_stock_length_that_stands_high_enough():
    so = fastener_table().standoff("M2.5")
    assert so.pick_length(15.0) == 15.0 and so.pick_length(15.01) == 20.0 and so.pick_length(0.1) == min(so.stock_lengths_mm)
    with pytest.raises(ValueError, match="no stock m2p5_standoff is 31 mm or longer"):
        so.pick_length(31.0)
    with pytest.raises(ValueError, match="no standoff for thread 'M3'"):
        fastener_table().standoff("M3")


def test_a_standoff_is_its_hex_body_on_its_stud(rig):
    """Volume of the solid against the hexagon's area (3 sqrt(3) / 2 x circumradius^2) x length plus the stud."""
    from cad.bought.fasteners import Standoff
    s = Standoff.from_rig(rig, "m2p5_standoff", "M2.5", 15.0)
    af = rig.dim("m2p5_standoff", "across_flats_mm")
    hexagon = 3 * math.sqrt(3) / 2 * (af / math.sqrt(3)) ** 2
    shape = s.build()
    assert shape.isValid() and len(shape.Solids()) == 1
    assert shape.Volume() == pytest.approx(hexagon * 15.0 + s.stud_volume_mm3(), rel=1e-3)
    bb = shape.BoundingBox()
    assert bb.zmin == pytest.approx(-s.stud_mm) and bb.zmax == pytest.approx(15.0)
    assert bb.ymax - bb.ymin == pytest.approx(af, abs=1e-6)
    assert s.bom_key == "m2p5_standoff:M2.5x15"


@pytest.mark.slow
def test_the_card_stands_on_a_standoff_under_each_hole_screwed_through_its_board(asm):
    """Each standoff's foot on the devkit's top, its top on the card's underside, under a card hole;
    each card screw's axis through a standoff's, its thread inside the standoff's female depth."""
    cp = asm.layout.compute
    feet = [n for n in asm.nodes if n.props.get("kind") == "standoff"]
    screws = {j.host: j for j in asm.layout.joints if j.name.startswith("card_")}
    holes = [cp.card_pose.apply(np.array(p)) for p in cp.card.mount_points()]
    assert len(feet) == len(holes) == len(screws) == 4
    for n in feet:
        bb = n.shape(asm.cache).BoundingBox()
        assert bb.zmin == pytest.approx(cp.orin_box.hi[2] - n.spec.stud_mm, abs=0.01)   # OCC boxes a cylinder loosely
        assert bb.zmax == pytest.approx(cp.card_box.lo[2], abs=1e-6)
        assert min(math.hypot(h[0] - n.pose.t[0], h[1] - n.pose.t[1]) for h in holes) < 1e-9
        j = screws[n.name]
        assert j.screw_id == "m2p5_machine_screw" and j.head[:2] == pytest.approx(tuple(n.pose.t[:2]))
        assert 0 < j.engagement_mm <= n.spec.female_depth_mm
