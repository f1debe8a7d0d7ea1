"""The BOM is the CAD assembly joined with the catalogue: counts, masses, filament, packs, outputs."""
from __future__ import annotations

import copy
import math
import re

import pytest
import yaml

from cad.build import main as build_main
from platform_tools.rig import load_rig

from .conftest import REPO, read_bom

#: the bill is counted from the built CAD assembly: the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow

CATALOGUE = REPO / "bom" / "parts.yaml"


@pytest.fixture(scope="module")
def tree():
    from cad.assembly import assembly_tree, build
    return assembly_tree(build(load_rig()))


@pytest.mark.slow
def test_quantities_come_from_the_assembly(bom_default, tree):
    rows = read_bom(bom_default)
    for key, count in tree["counts"].items():
        if tree["made_parts"].get(key, {}).get("category") == "printed":
            continue
        assert float(rows[key]["quantity"]) == count, key
    # every screw length is its own line, bought in whole packs
    screws = {k: r for k, r in rows.items() if k.startswith("m3_screw:")}
    assert set(screws) == {k for k in tree["counts"] if k.startswith("m3_screw:")}
    for r in screws.values():
        assert int(r["packs"]) == math.ceil(float(r["quantity"]) / int(r["pack_size"]))


def test_masses_and_filament(bom_default, tree):
    rig = load_rig()
    rows = read_bom(bom_default)
    assert float(rows["jetson_agx_orin"]["mass_g"]) == rig.part("jetson_agx_orin").mass_g.value
    hs = tree["made_parts"]["heat_sink"]
    assert float(rows["heat_sink"]["mass_g"]) == pytest.approx(hs["mass_g"] * 2, abs=0.2)
    printed = sum(v["mass_g"] * v["quantity"] for v in tree["made_parts"].values() if v["category"] == "printed")
    waste = yaml.safe_load(CATALOGUE.read_text())["parts"]["petg_filament"]["supply"]["waste_percent"]
    assert float(rows["petg_filament"]["quantity"]) == pytest.approx(printed * (1 + waste / 100), abs=2)
    assert float(rows["petg_filament"]["mass_g"]) == 0          # counted on the printed parts' lines
    total = rows["total"]
    assert float(total["cost"]) == pytest.approx(sum(float(r["cost"]) for k, r in rows.items() if k != "total"), abs=0.05)
    assert float(total["mass_g"]) == pytest.approx(sum(float(r["mass_g"]) for k, r in rows.items() if k != "total"), abs=0.5)


def test_md_and_html_group_by_category(bom_default):
    md = (bom_default / "bom.md").read_text()
    html = (bom_default / "bom.html").read_text()
    for cat in ("sensors", "compute", "power", "thermal", "fasteners", "cables", "printed"):
        assert f"## {cat}" in md and f"subtotal {cat}" in html
    assert "M3 x 10 mm" in md and "https://store.stereolabs.com/products/zed-x" in html
    assert 'id="made-parts"' in html and "fits" in html


@pytest.mark.slow
def test_bom_follows_the_rig(bom_default, bom_changed):
    a, b = read_bom(bom_default), read_bom(bom_changed)
    assert float(a["handle"]["quantity"]) == 3 and float(b["handle"]["quantity"]) == 1
    assert float(b["m3_screw:M3x10"]["quantity"]) == float(a["m3_screw:M3x10"]["quantity"]) - 8
    assert float(b["m3_insert"]["quantity"]) == float(a["m3_insert"]["quantity"]) - 8
    assert float(b["thermal_mount"]["mass_g"]) > float(a["thermal_mount"]["mass_g"])   # a longer bar
    assert float(b["petg_filament"]["quantity"]) < float(a["petg_filament"]["quantity"])
    assert float(b["total"]["mass_g"]) < float(a["total"]["mass_g"])


# ------------------------------------------------------------------------------- bad input
def _catalogue(tmp_path, edit) -> str:
    data = yaml.safe_load(CATALOGUE.read_text())
    edit(data)
    p = tmp_path / "parts.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return str(p)


def _dup_number(d):
    d["parts"]["sync_spare"] = dict(d["parts"]["sync_harness"])


def _unused(d):
    d["parts"]["heat_sink_spare"] = dict(d["parts"]["heat_sink"])


def _written_filament(d):
    d["parts"]["petg_filament"]["supply"]["quantity"] = 1000


@pytest.mark.slow
@pytest.mark.parametrize("edit, expected", [
    (lambda d: d["parts"]["zed_x"].pop("price"), "parts.zed_x.price: is missing"),
    (lambda d: d["parts"]["zed_x"]["price"].update(currency="US$"), "parts.zed_x.price.currency: got 'US$'"),
    (lambda d: d["parts"]["zed_x"]["price"].update(currency="GBP") or d["exchange_rates"].pop("GBP"),
     "parts.zed_x.price.currency: is GBP, which has no rate"),
    (_dup_number, "parts.sync_spare: has part number 'JST-GH 1.25 mm pigtails and 26 AWG wire (Y harness)', already "
                  "used by parts.sync_harness"),
    (lambda d: d["parts"].pop("quarter20_screw"), "parts.quarter20_screw: missing: the CAD assembly places "
                                                  "quarter20_screw (screw_zed_x_0)"),
    (lambda d: d["parts"].pop("heat_sink"), "parts.heat_sink: missing"),
    (_unused, "parts.heat_sink_spare: used nowhere"),
    (_written_filament, "parts.petg_filament.supply.quantity: is 1000, but quantity_from: printed_parts computes it"),
    (lambda d: d["parts"]["boson_lens_4p9mm"].update(price=dict(amount=350, currency="USD", checked="2026-11-01",
                                                                confidence="estimate")),
     "parts.boson_lens_4p9mm.price: comes fitted to boson_640 (included_with)"),
    (lambda d: d["parts"]["boson_lens_4p9mm"].pop("included_with"), "parts.boson_lens_4p9mm.price: is missing"),
    (lambda d: d["parts"]["fan_3010_5v"].pop("generic"), "parts.fan_3010_5v.link: is a shop search"),
    (lambda d: d["parts"]["zed_x"].update(link="https://www.amazon.com/s?k=zed+x"), "parts.zed_x.link: is a shop search"),
    (lambda d: d["parts"]["boson_sync_breakout"].pop("generic"),
     "parts.boson_sync_breakout: has vendor generic and no maker part"),
    (lambda d: d["parts"]["power_switch"].update(generic="no MPN verified"),
     "parts.power_switch.generic: is given with part"),
])
def test_bad_catalogue(tmp_path, capsys, edit, expected):
    bad = _catalogue(tmp_path, edit)
    out = tmp_path / "out"
    out.mkdir()
    (out / "bom.csv").write_text("previous output\n")
    code = build_main(["bom", "--catalogue", bad, "--out", str(out), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert expected in err and str(bad) in err, err
    assert "Traceback" not in err
    assert (out / "bom.csv").read_text() == "previous output\n"        # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "parts.yaml"]   # no staging left behind


def test_bad_catalogue_names_the_line(tmp_path, capsys):
    text = CATALOGUE.read_text().replace("currency: USD, checked: \"2026-11-01\", confidence: estimate}\n  boson_640:",
                                         "currency: XYZ, checked: \"2026-11-01\", confidence: estimate}\n  boson_640:")
    bad = tmp_path / "parts.yaml"
    bad.write_text(text)
    code = build_main(["bom", "--catalogue", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    line = next(i for i, ln in enumerate(text.splitlines(), 1) if "XYZ" in ln)
    assert code == 2 and f"{bad}:{line}: parts.zed_x.price.currency: got 'XYZ'" in err, err
    assert not (tmp_path / "out").exists()


def test_power_and_sync_lines(bom_default):
    rows = read_bom(bom_default)
    lens = rows["boson_lens_4p9mm"]
    assert float(lens["cost"]) == 0 and "fitted to boson_640" in lens["price_note"]
    for key in ("makita_charger", "wifi_pigtail", "power_splices"):   # the fuse holder's fixings: counted from the model
        assert float(rows[key]["quantity"]) > 0, key


def test_the_capture_card_fixings_are_counted_from_the_model(bom_default, rig):
    """The kit line is gone: one standoff and one screw per hole of the card's board (the rig's holes),
    each a line per length from the CAD assembly; the standoff 15 mm long, the gap the devkit's 60 mm fan
    asks under the card (0.25 x 60, a stock length)."""
    rows = read_bom(bom_default)
    assert "capture_card_fixings" not in rows
    holes = len(next(m for m in rig.part("zed_link_quad").mounting if m.face.value == "bottom").positions_mm)
    standoffs = [k for k in rows if k.startswith("m2p5_standoff:")]
    screws = [k for k in rows if k.startswith("m2p5_machine_screw:")]
    assert len(standoffs) == 1 and len(screws) == 1, (standoffs, screws)
    for key in standoffs + screws:
        assert rows[key]["source"] == "CAD assembly" and float(rows[key]["quantity"]) == holes, key
    assert standoffs[0] == "m2p5_standoff:M2.5x15"
    assert "M2.5 x 15 mm" in rows[standoffs[0]]["name"] and "15mm" in rows[standoffs[0]]["link"]
    # the gland, the cut-off and the breakouts are counted from the CAD model, one breakout per Boson
    for key in ("undervoltage_cutoff", "cable_gland", "boson_sync_breakout"):
        assert rows[key]["source"] == "CAD assembly", key
    assert float(rows["cable_gland"]["quantity"]) == 1 and float(rows["undervoltage_cutoff"]["quantity"]) == 1
    assert float(rows["boson_sync_breakout"]["quantity"]) == float(rows["boson_640"]["quantity"]) == 2
    assert float(rows["wifi_pigtail"]["quantity"]) == float(rows["wifi_antenna"]["quantity"])


def test_cables_bought_at_the_length_their_route_needs(bom_default):
    """The GMSL2 cable and the pigtails are counted from the routes of cad/cables.py, at the stock length the
    route plus its slack needs; the cables table of bom.html gives each route's length."""
    import re
    from cad.bought.cables import cable_table
    rows = read_bom(bom_default)
    html = (bom_default / "bom.html").read_text()
    routes = {m[0]: (float(m[1]), float(m[2])) for m in
              re.findall(r'id="cable-([a-z0-9-]+)" data-route-mm="([0-9.]+)" data-bought-mm="([0-9.]+)"', html)}
    assert {"gmsl2", "pigtail-left", "pigtail-right", "sync-left", "sync-right"} <= set(routes), routes
    k = cable_table().kinds["gmsl2_coax"]
    route, bought = routes["gmsl2"]
    assert bought == min(s for s in k.stock_lengths_mm if s >= route + k.service_slack_mm)
    g = rows["gmsl2_cable"]
    assert g["source"] == "cable routes" and float(g["quantity"]) == 1 and f"{bought:g} mm" in g["part_number"]
    p = rows["wifi_pigtail"]
    assert p["source"] == "cable routes" and f"{routes['pigtail-left'][1]:g} mm" in p["part_number"]
    # the Bosons' USB cables: one per route, at the stock length the longer of the two needs (recomputed here
    # from the routes' lengths in bom.html and the cable table's stock lengths)
    ku = cable_table().kinds["usb_lead"]
    need = max(routes["usb-left"][0], routes["usb-right"][0]) + ku.service_slack_mm
    u = rows["boson_usb_cable"]
    assert float(u["quantity"]) == 2 and f"{min(s for s in ku.stock_lengths_mm if s >= need):g} mm" in u["part_number"]
    kd = cable_table().kinds["dc_lead"]
    d = rows["orin_dc_plug"]
    assert float(d["quantity"]) == 1 and f"{min(s for s in kd.stock_lengths_mm if s >= routes['dc-lead'][0] + kd.service_slack_mm):g} mm" in d["part_number"]


def test_cable_routes_supply_with_a_quantity_is_refused(tmp_path, capsys):
    text = CATALOGUE.read_text().replace("      quantity_from: cable_routes   # the route of cad/cables.py",
                                         "      quantity: 1\n      quantity_from: cable_routes   # the route of cad/cables.py")
    bad = tmp_path / "parts.yaml"
    bad.write_text(text)
    code = build_main(["bom", "--catalogue", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "parts.gmsl2_cable.supply.quantity: is 1, but quantity_from: cable_routes computes it" in err, err
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------------------- what to order
#: shop search pages, spelled here apart from bom.catalogue's own rule: the search forms of the shops the
#: catalogue has linked (amazon /s?k=, McMaster-Carr ?s=, a /search? path)
SEARCH_FORMS = re.compile(r"amazon\.[a-z.]+/s\?k=|mcmaster\.com/[^?]*\?s=|/search\?")


def _entries() -> dict:
    return yaml.safe_load(CATALOGUE.read_text())["parts"]


def test_no_entry_links_to_a_search_unless_marked_generic():
    entries = _entries()
    searches = {pid for pid, e in entries.items() if SEARCH_FORMS.search(e["link"])}
    assert searches, "the catalogue still buys generic parts through a search; this test has nothing to check"
    for pid in searches:
        assert "generic" in entries[pid] and "part" not in entries[pid], pid
    for pid, e in entries.items():
        if "part" in e:
            assert not SEARCH_FORMS.search(e["link"]), pid


def _rig_parts() -> dict:
    """config/rig.yaml's parts, read as plain YAML (not through the rig loader the BOM uses)."""
    return yaml.safe_load((REPO / "config" / "rig.yaml").read_text())["parts"]


def _maker_mpn(pid: str, p: dict, rig_parts: dict) -> tuple[str, str]:
    """Who makes an entry's maker part: its own maker/MPN (a supply, a candidate), else the rig part's."""
    if "maker" in p:
        return p["maker"], p["mpn"]
    return rig_parts[pid]["vendor"], rig_parts[pid]["part_number"]


def test_every_maker_part_has_a_maker_and_a_source():
    """Maker and MPN are said once: a rig part's in config/rig.yaml only (not generic there), a supply's or a
    candidate's in its own part block."""
    parts, rig_parts = {pid: e["part"] for pid, e in _entries().items() if "part" in e}, _rig_parts()
    assert parts
    assert any(pid in rig_parts and "maker" not in p for pid, p in parts.items()), "no part block reads the rig's"
    for pid, p in parts.items():
        if pid in rig_parts and "candidate" not in p:
            assert "maker" not in p and "mpn" not in p, pid
            assert rig_parts[pid]["vendor"].lower() != "generic", pid
        else:
            assert p["maker"].strip() and p["mpn"].strip(), pid
        if p["verified"]:
            assert p["source"].startswith("https://"), pid
        else:
            assert p["source"].lower().startswith("not verified here") and "ratings" not in p, pid


def _row(html: str, key: str) -> str:
    slug = re.sub(r"[^a-z0-9]+", "-", key.lower()).strip("-")
    m = re.search(rf'<tr id="line-{re.escape(slug)}">(.*?)</tr>', html, re.S)
    assert m, key
    return m.group(1)


def test_the_bom_shows_maker_mpn_source_and_generic_lines(bom_default):
    """Every line of an entry with a maker part shows maker, MPN and source in bom.csv, bom.html and bom.md;
    every line of a generic entry says so, and its shop link is shown as a search."""
    entries, rows, rig_parts = _entries(), read_bom(bom_default), _rig_parts()
    html, md = (bom_default / "bom.html").read_text(), (bom_default / "bom.md").read_text()
    seen = {"part": 0, "generic": 0, "candidate": 0}
    for key, r in rows.items():
        e = entries.get(key.split(":")[0])
        if key == "total" or e is None or r["vendor"] == "printed":
            continue
        cell = _row(html, key)
        if "part" in e:
            p = e["part"]
            maker, mpn = _maker_mpn(key.split(":")[0], p, rig_parts)
            assert (r["maker"], r["mpn"], r["mpn_source"]) == (maker, mpn, p["source"]), key
            if "candidate" in p:
                assert r["mpn_status"] == "candidate: does not fit the CAD model yet", key
                assert " ".join(p["candidate"].split()) in r["order_note"], key
                seen["candidate"] += 1
            else:
                assert r["mpn_status"] == ("MPN verified" if p["verified"] else "MPN not verified"), key
            assert maker in cell and mpn in cell and p["source"] in cell, key
            assert f"{maker} / {mpn}" in md, key
            seen["part"] += 1
        elif "generic" in e:
            assert r["mpn_status"] == "generic: no MPN verified" and "generic: no MPN verified" in cell, key
            assert (">search: " in cell) == bool(SEARCH_FORMS.search(r["link"])), key
            seen["generic"] += 1
    assert seen["part"] and seen["generic"], seen
    verified = sum(1 for r in rows.values() if r["mpn_status"] == "MPN verified")
    generic = sum(1 for r in rows.values() if r["mpn_status"] == "generic: no MPN verified")
    assert f'What to order: <span class="ok">{verified}</span> lines' in html
    assert f'<span class="generic">{generic} are generic</span>' in html


def _catalogue_problems(tmp_path, rig, edit) -> str:
    """The problems load_catalogue reports for the shipped catalogue changed by ``edit`` ("" if none)."""
    from bom.catalogue import CatalogueError, load_catalogue
    data = copy.deepcopy(yaml.safe_load(CATALOGUE.read_text()))
    edit(data)
    path = tmp_path / "parts.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    try:
        load_catalogue(rig, path)
    except CatalogueError as exc:
        return str(exc)
    return ""


def _battery(rig):
    return next(p for p in rig.desc.parts.values() if p.kind.value == "battery")


def test_a_maker_part_rated_below_what_the_rig_assumes_is_refused(tmp_path, rig):
    """The switch must break the current cad/electrical.py sizes it for, at the pack's full voltage or the
    DC voltage config/rig.yaml assumes of it, whichever is higher."""
    switch = rig.part("power_switch")
    need_a = switch.rating_a.value
    need_v = max(_battery(rig).output_v.max, switch.rating_dc_v.value)

    def weak_switch(d):
        d["parts"]["power_switch"]["part"]["ratings"] = {"dc_current_a": need_a / 2, "dc_voltage_v": need_v - 1}
    err = _catalogue_problems(tmp_path, rig, weak_switch)
    assert f"parts.power_switch.part.ratings.dc_current_a: L1141A801-AGZ00-000 is rated {need_a / 2:g} A; " \
           f"config/rig.yaml assumes {need_a:g} A" in err, err
    assert "parts.power_switch.part.ratings.dc_voltage_v:" in err and f"must stand {need_v:g} V" in err, err
    assert len(err.splitlines()) == 2, err
    at_limit = _catalogue_problems(tmp_path, rig, lambda d: d["parts"]["power_switch"]["part"].update(
        ratings={"dc_current_a": need_a, "dc_voltage_v": need_v}))
    assert at_limit == ""


def _converter(d, **ratings):
    e = d["parts"]["dc_converter"]
    e.pop("generic", None)
    e["link"] = "https://example.org/ex-150-12"
    e["part"] = {"maker": "Example Power", "mpn": "EX-150-12", "source": "https://example.org/ex-150-12",
                 "verified": True, "ratings": ratings, "candidate": "a test part the rig does not describe"}


def test_a_converter_must_take_the_battery_from_cut_off_to_full(tmp_path, rig):
    bat = _battery(rig)
    low = bat.cutoff_v.value
    conv = rig.part("dc_converter")
    out = {"min": conv.output_v.min, "max": conv.output_v.max}
    ok = _catalogue_problems(tmp_path, rig, lambda d: _converter(
        d, input_v={"min": low - 1, "max": bat.output_v.max + 10}, output_v=out,
        dc_current_a=conv.rating_a.value))
    assert ok == ""
    narrow = _catalogue_problems(tmp_path, rig, lambda d: _converter(
        d, input_v={"min": low + 1.8, "max": bat.output_v.max + 10}, output_v=out))
    assert "parts.dc_converter.part.ratings.input_v: EX-150-12 works from" in narrow and \
           f"the battery gives {low:g} V (cut-off)" in narrow, narrow
    wrong_out = _catalogue_problems(tmp_path, rig, lambda d: _converter(
        d, output_v={"min": conv.output_v.max + 7, "max": conv.output_v.max + 7}))
    assert "parts.dc_converter.part.ratings.output_v:" in wrong_out, wrong_out


@pytest.mark.parametrize("part, expected", [
    ({"verified": False, "source": "https://example.org/page"}, "part.source: is 'https://example.org/page'; an MPN "
                                                                 "not verified here needs a source starting"),
    ({"verified": True, "source": "a forum post"}, "part.source: is 'a forum post'; verified: true needs the address"),
    ({"verified": False, "source": "not verified here: a forum post", "ratings": {"dc_current_a": 30}},
     "part.ratings: are given for an MPN not verified here"),
])
def test_a_maker_part_says_where_its_mpn_was_read(tmp_path, rig, part, expected):
    def edit(d):
        d["parts"]["power_switch"]["part"].pop("ratings")
        d["parts"]["power_switch"]["part"].update(part)
    err = _catalogue_problems(tmp_path, rig, edit)
    assert "parts.power_switch." + expected in err, err


def test_a_rig_part_says_its_maker_and_mpn_once(tmp_path, rig):
    """The switch's maker and MPN are config/rig.yaml's: repeating them in its part block is refused, with
    the rig key that holds them; a candidate naming the part the rig already describes is refused too."""
    def repeat(d):
        d["parts"]["power_switch"]["part"].update(maker=rig.part("power_switch").vendor, mpn="L1141A801-AGZ00-000")
    err = _catalogue_problems(tmp_path, rig, repeat)
    assert "parts.power_switch.part.maker: is 'Carling Technologies'; the rig description holds it " \
           "(config/rig.yaml parts.power_switch.vendor" in err, err
    assert "parts.power_switch.part.mpn:" in err and "parts.power_switch.part_number" in err, err
    assert len(err.splitlines()) == 2, err
    def same_candidate(d):
        repeat(d)
        d["parts"]["power_switch"]["part"]["candidate"] = "does not fit"
    err = _catalogue_problems(tmp_path, rig, same_candidate)
    assert "parts.power_switch.part.candidate: is given, but config/rig.yaml parts.power_switch already is" in err, err
    def nameless_candidate(d):
        _converter(d)   # a candidate for another converter than the rig's TEP 150-2412WI, its MPN left out
        d["parts"]["dc_converter"]["part"].pop("mpn")
    err = _catalogue_problems(tmp_path, rig, nameless_candidate)
    assert "parts.dc_converter.part.mpn: is missing; a candidate the rig description does not hold yet" in err, err


def test_the_docs_count_what_the_bom_says(bom_default):
    """docs/bom.md states how many lines are verified, candidates, named, made and generic: the default BOM
    agrees."""
    text = re.sub(r"\s+", " ", (REPO / "docs" / "bom.md").read_text())
    m = re.search(r"(\d+) lines\): (\d+) lines carry an MPN read on a stored .*?, (\d+) names? a candidate "
                  r".*?, (\d+) are named by their vendor.*?, (\d+) are printed or machined .*?, and (\d+) are "
                  r"generic", text)
    assert m, "docs/bom.md no longer states the counts"
    rows = [r for k, r in read_bom(bom_default).items() if k != "total"]
    status = [r["mpn_status"] for r in rows]
    assert [int(g) for g in m.groups()] == [len(rows), status.count("MPN verified"),
                                            status.count("candidate: does not fit the CAD model yet"),
                                            status.count("named by its vendor, not verified here"),
                                            status.count("made from the CAD model"),
                                            status.count("generic: no MPN verified")]


def test_the_fuse_holder_fixings_are_counted_from_the_model(bom_default, tmp_path, rig_text):
    """No typed-in fixings line for the fuse holder: its tab screws and the inserts of its bosses are CAD
    nodes, counted on the M3 screw and insert lines; a holder with a third tab hole (its mounting given in the
    rig) adds one screw of that length and one insert to the bill."""
    from cad.layout import layout
    from .conftest import build_py
    a = read_bom(bom_default)
    assert "fuse_holder_fixings" not in a
    joints = [j for j in layout(load_rig()).joints if j.name.startswith("fuse_")]
    assert len(joints) == 2
    key = joints[0].screw.bom_key
    assert all(j.screw.bom_key == key for j in joints) and a[key]["source"] == "CAD assembly"
    data = yaml.safe_load(rig_text)
    data["parts"]["blade_fuse"]["mounting"] = [{"face": "bottom", "thread": "M3", "depth_mm": 2,
                                                "positions_mm": [[-16, 0], [16, -3], [16, 3]],
                                                "source": "estimate", "confidence": "estimate"}]
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    r = build_py("bom", "--out", str(tmp_path / "out"), "--rig", str(path), "-q")
    assert r.returncode == 0, r.stderr
    b = read_bom(tmp_path / "out")
    assert float(b[key]["quantity"]) == float(a[key]["quantity"]) + 1
    assert float(b["m3_insert"]["quantity"]) == float(a["m3_insert"]["quantity"]) + 1
