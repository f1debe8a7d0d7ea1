"""The fastener table answers what a joint asks of a thread; joints hold typed fasteners."""
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
