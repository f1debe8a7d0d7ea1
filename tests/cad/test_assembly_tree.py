"""What the BOM reads: part ids, quantities, placements, fasteners from the geometry."""
from cad.assembly import assembly_tree
from cad.bought.fasteners import fastener_table


def test_every_joint_places_its_fasteners(asm):
    joints = asm.layout.joints
    standoffs = [n for n in asm.nodes if n.props.get("kind") == "standoff"]
    screws = [n for n in asm.nodes if n.category == "fastener" and n.part_id != "m3_insert" and n not in standoffs]
    inserts = asm.by_part("m3_insert")
    assert len(screws) == len(joints)
    assert len(inserts) == sum(j.kind == "insert" for j in joints)
    assert all(n.props["length_mm"] in fastener_table().stock_lengths_mm for n in screws)
    # the capture card's standoffs: one per screw driven into one, each a stock standoff length
    assert len(standoffs) == sum(j.host in {n.name for n in standoffs} for j in joints) == 4
    assert all(n.props["length_mm"] in fastener_table().standoff(n.props["thread"]).stock_lengths_mm for n in standoffs)


def test_tree_counts_and_placements(asm):
    tree = assembly_tree(asm)
    leaves = [leaf for g in tree["children"] for leaf in g["children"]]
    assert len(leaves) == len(asm.nodes)
    assert sum(tree["counts"].values()) == len(asm.nodes)
    assert tree["counts"]["handle"] == 3 and tree["counts"]["orin_standoff"] == 4
    assert tree["counts"]["boson_640"] == 2 and tree["counts"]["fan_3010_5v"] == 2
    assert all(len(leaf["placement"]) == 4 for leaf in leaves)
    made = tree["made_parts"]
    assert made["case_lower"]["volume_mm3"] > 0 and "print_orientation_rpy_deg" in made["case_lid"]
    assert made["heat_sink"]["category"] == "machined" and made["heat_sink"]["quantity"] == 2
