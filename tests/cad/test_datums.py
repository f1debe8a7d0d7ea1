"""Camera datums (cad/datums.py): every camera held in six degrees of freedom by named features, each
feature removing what it claims, the features present in the built geometry; deliberate defects fail."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cad.datums import Contact, Feature, Location, camera_locations, datum_problems, describe, free_motions
from platform_tools.rig.frames import Pose


@pytest.fixture(scope="module")
def locations(rig):
    from cad.layout import layout
    return camera_locations(layout(rig))


def _without(locations, camera, feature):
    out = dict(locations)
    out[camera] = tuple(dataclasses.replace(loc, features=tuple(f for f in loc.features if f.name != feature))
                        for loc in locations[camera])
    return out


def test_a_block_on_a_plane_keeps_the_three_motions_a_plane_allows():
    # an independent case by hand: three contacts under a block, normals up: it still slides in x, y and turns in yaw
    I = Pose.identity()
    c = [Contact(p, (0.0, 0.0, 1.0), (("t", 0.1, False),)) for p in ((0, 0, 0), (10, 0, 0), (0, 10, 0))]
    loc = Location("block on plane", "block", "plane", (Feature("plane", "plane", ("z", "roll", "pitch"), tuple(c)),), I)
    free = free_motions(loc.rows())
    assert len(free) == 3 and sorted(describe(free)) == ["x", "y", "yaw"]
    # a wall along x (two contacts, normal y) and an end stop (normal x) hold it: the 3-2-1 scheme
    wall = Feature("wall", "plane", ("y", "yaw"), tuple(Contact(p, (0.0, 1.0, 0.0), ()) for p in ((0, 0, 5), (10, 0, 5))))
    stop = Feature("stop", "plane", ("x",), (Contact((0, 5, 5), (1.0, 0, 0), ()),))
    held = dataclasses.replace(loc, features=loc.features + (wall, stop))
    assert len(free_motions(held.rows())) == 0


@pytest.mark.slow
def test_every_camera_is_held_in_six_dof_by_named_features(locations):
    assert set(locations) == {"zed_x", "thermal_left", "thermal_right"}
    bad, details = datum_problems(locations)
    assert not bad, bad
    # the chains end at the cameras and start at the case floor
    for cam, chain in locations.items():
        assert chain[0].base == "case_lower"
        assert chain[-1].moving == ("zed_x" if cam == "zed_x" else f"boson_{cam.split('_')[1]}")
    names = {f.name for chain in locations.values() for loc in chain for f in loc.features}
    assert {"rear registration lip", "1/4-20 screw in the shelf's hole", "front stop ring",
            "bore floor (flat: clocks the roll)"} <= names


@pytest.mark.slow
def test_without_the_lip_the_zed_slides_back_and_turns(locations):
    bad, _ = datum_problems(_without(locations, "zed_x", "rear registration lip"))
    assert len(bad) == 1 and "zed_x on zed_mount" in bad[0]
    assert "yaw" in bad[0] and "x" in bad[0].split("(")[1]


@pytest.mark.slow
def test_without_the_front_stop_the_boson_slides_along_its_axis(locations):
    bad, _ = datum_problems(_without(locations, "thermal_left", "front stop ring"))
    # and the retaining plate then presses the core onto nothing
    assert bad == ["thermal_left: boson_left in heat_sink_left: retaining plate presses 'front stop ring', which is "
                   "no feature of it",
                   "thermal_left: boson_left in heat_sink_left: free to move (x): add a datum feature"]


@pytest.mark.slow
def test_a_feature_claiming_what_it_does_not_remove_is_caught(locations):
    chain = locations["zed_x"]
    shelf = chain[1]
    wrong = tuple(dataclasses.replace(f, removes=("y",)) if f.name == "rear registration lip" else f
                  for f in shelf.features)
    bad, _ = datum_problems({"zed_x": (chain[0], dataclasses.replace(shelf, features=wrong))})
    assert len(bad) == 1 and "claims y" in bad[0] and "yaw" in bad[0]


@pytest.mark.slow
def test_the_datum_features_are_in_the_built_geometry(asm):
    from cad import checks
    r = checks.check_datums(asm)
    assert r.ok, r.details[:5]
    assert set(r.data) == {"zed_x", "thermal_left", "thermal_right"}


@pytest.mark.slow
def test_a_mount_without_its_lip_fails_the_check(asm):
    # the ZED mount built without its registration lip: the lip's contacts are off the part
    from cad import checks
    from cad.assembly import Assembly
    nodes = [dataclasses.replace(n, spec=dataclasses.replace(n.spec, lip=None), _shape=None) if n.name == "zed_mount"
             else n for n in asm.nodes]
    r = checks.check_datums(Assembly(asm.rig, asm.layout, nodes, asm.cache))
    assert not r.ok
    off = [d for d in r.details if "not in the geometry" in d]
    assert off and all("rear registration lip" in d and "zed_mount" in d for d in off)


@pytest.mark.slow
def test_the_heat_sink_has_its_stop_and_the_boson_touches_it(asm):
    # independent of the datum model: the copper in front of the Boson's front face, read off the solids
    from cad.solids import bounds_of
    lay = asm.layout
    hs = asm.node("heat_sink_left").shape(asm.cache)
    core_front = lay.cameras.thermal["left"].pose.apply(np.array([lay.cameras.core.bounds().hi[0], 0, 0]))[0]
    assert bounds_of(hs).hi[0] == pytest.approx(core_front + asm.rig.desc.enclosure.heat_sink.stop_mm, abs=1e-3)
    lens = asm.node("boson_lens_left").shape(asm.cache)
    assert hs.intersect(lens).Volume() < 1e-3          # the lens passes through the ring
