"""The generated site in a real browser, and the guide following the rig."""
from __future__ import annotations

import re
import shutil
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from cad.build import main as build_main
from tests.bom.conftest import REPO

#: every test reads the generated site (CAD pictures) in a browser: the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow

PAGES = ["index.html", "assembly.html", "bom.html", "wiring.html", "printing.html"]
SCREENSHOT = REPO / "build" / "test-screenshots" / "docs_index.png"

INFO = """return {
  ready: document.readyState,
  title: document.title,
  images: Array.from(document.images).map(i => ({src: i.src, complete: i.complete, w: i.naturalWidth,
                                                 h: i.naturalHeight, shownW: i.getBoundingClientRect().width})),
  links: Array.from(document.querySelectorAll('a[href], link[href]')).map(a => a.href),
  ids: Array.from(document.querySelectorAll('[id]')).map(e => e.id),
};"""


@pytest.mark.slow
def test_every_page_loads_with_its_images_and_links(docs_default, browser):
    ids: dict[Path, set[str]] = {}
    links: list[tuple[str, str]] = []
    for name in PAGES:
        browser.get((docs_default / name).as_uri())
        info = browser.execute_script(INFO)
        assert info["ready"] == "complete" and info["title"], name
        assert info["images"] or name == "bom.html", f"{name} shows no picture"
        for img in info["images"]:
            assert img["complete"] and img["w"] > 0 and img["h"] > 0, f"{name}: image {img['src']} did not load"
            assert img["shownW"] > 50, f"{name}: image {img['src']} is drawn {img['shownW']} px wide"
        ids[docs_default / name] = set(info["ids"])
        links += [(name, href) for href in info["links"]]
    internal = [(page, h) for page, h in links if h.startswith("file://")]
    assert len(internal) > 30
    for page, href in internal:
        url = urlparse(href)
        target = Path(unquote(url.path))
        assert target.is_file(), f"{page}: link {href} points at nothing"
        assert docs_default in target.parents, f"{page}: link {href} leaves the site"
        if url.fragment:
            if target not in ids:
                browser.get(target.as_uri())
                ids[target] = set(browser.execute_script(INFO)["ids"])
            assert url.fragment in ids[target], f"{page}: link {href}: no element with id {url.fragment!r}"
    # the index page, for a human to look at
    browser.get((docs_default / "index.html").as_uri())
    SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
    assert browser.save_screenshot(str(SCREENSHOT)) and SCREENSHOT.stat().st_size > 20_000


def test_wiring_is_drawn_from_the_rig(docs_default):
    svg = (docs_default / "wiring.svg").read_text()
    from platform_tools.rig import load_rig
    rig = load_rig()
    s, b = rig.desc.sync, rig.desc.recording.button
    assert f"{s.connector}.{s.signal_pin}: {s.level_v:g} V, {s.edge} edge" in svg
    assert f"{s.connector}.{s.ground_pin} GND" in svg
    assert f"pin {b.gpio_pin} (button), pin {b.led_pin} (LED)" in svg
    assert svg.count('data-to="boson_') == 4 and "FAILS" not in (docs_default / "wiring.html").read_text()


def _step(md: str, title_part: str) -> str:
    parts = re.split(r"\n## ", md)
    return next(p for p in parts if title_part in p.splitlines()[0])


@pytest.mark.slow
def test_guide_follows_the_rig(docs_default, docs_changed):
    a, b = (d / "assembly.md" for d in (docs_default, docs_changed))
    lid_a, lid_b = _step(a.read_text(), "handles"), _step(b.read_text(), "handles")
    assert "3 x handle" in lid_a and "1 x handle" in lid_b
    assert "12 x **M3 x 10 mm**" in lid_a and "4 x **M3 x 10 mm**" in lid_b
    assert "120 mm apart" in _step(a.read_text(), "Boson") and "130 mm apart" in _step(b.read_text(), "Boson")
    # the pictures are re-rendered from the changed model
    assert (docs_default / "img/step_10.png").read_bytes() != (docs_changed / "img/step_10.png").read_bytes()


def test_guide_content(docs_default):
    md = (docs_default / "assembly.md").read_text()
    assert "245 °C for PETG" in md and "thermal paste" in md and "J17 pin 16 (signal) and pin 2 (ground)" in md
    html = (docs_default / "assembly.html").read_text()
    assert html.count('<section class="step"') == len(list((docs_default / "img").glob("step_[0-9][0-9].png")))


# ------------------------------------------------------------------------------- bad steps
STEPS = REPO / "docs" / "assembly" / "steps.yaml"


@pytest.mark.slow
@pytest.mark.parametrize("old, new, expected", [
    ("nodes: [zed_mount, insert_zed_mount_*", "nodes: [zed_mout, insert_zed_mount_*",
     "steps[4].nodes[0]: 'zed_mout' is not a node of the CAD assembly (did you mean 'zed_mount'?)"),
    ("    supplies: [thermal_paste]\n", "",
     "BOM line 'thermal_paste' (between each Boson body and its copper heat sink) is used by no step"),
    ("nodes: [makita_battery]", "nodes: [jetson_agx_orin]", "no step adds 1 node(s) of the CAD assembly: makita_battery"),
    ("{{ sync.signal_pin }} (signal)", "{{ sync.signal_pinn }} (signal)", "'signal_pinn'"),
])
def test_bad_steps(tmp_path, capsys, old, new, expected):
    text = STEPS.read_text()
    assert old in text
    bad = tmp_path / "steps.yaml"
    bad.write_text(text.replace(old, new))
    out = tmp_path / "docs"
    out.mkdir()
    (out / "index.html").write_text("previous")
    code = build_main(["docs", "--steps", str(bad), "--out", str(out), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert expected in err and str(bad) in err, err
    assert "Traceback" not in err
    assert [p.name for p in out.iterdir()] == ["index.html"] and (out / "index.html").read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["docs", "steps.yaml"]


STEP_TIMES = """return {
  total: Number(document.querySelector('p.time-total').dataset.minutes),
  steps: Array.from(document.querySelectorAll('section.step')).map(s => {
    const t = s.querySelector('p.time');
    const items = h => Array.from(s.querySelectorAll('h3')).filter(e => e.textContent === h)
        .flatMap(e => Array.from(e.nextElementSibling.querySelectorAll('li')));
    const sum = h => items(h).map(li => parseInt(li.textContent)).reduce((a, b) => a + b, 0);
    return {id: s.id, minutes: Number(t.dataset.minutes), insert: Number(t.dataset.insert),
            screw: Number(t.dataset.screw), part: Number(t.dataset.part), supply: Number(t.dataset.supply),
            shown: t.getBoundingClientRect().height > 0, fasteners: sum('Fasteners'), parts: sum('Parts'),
            supplies: items('Supplies').length};
  }),
};"""


def test_step_times_read_in_the_browser(docs_default, browser):
    """Each step's time, as the browser shows it, is the time table (docs/assembly/steps.yaml) times the
    operations listed on the page itself (fasteners, parts, supplies); the total is their sum."""
    import yaml
    minutes = yaml.safe_load(STEPS.read_text())["operation_minutes"]
    browser.get((docs_default / "assembly.html").as_uri())
    got = browser.execute_script(STEP_TIMES)
    assert len(got["steps"]) >= 10
    for s in got["steps"]:
        assert s["shown"], s["id"]
        assert s["insert"] + s["screw"] == s["fasteners"] and s["part"] == s["parts"] and s["supply"] == s["supplies"], s
        assert s["minutes"] == pytest.approx(sum(minutes[op] * s[op] for op in minutes)), s
    assert got["total"] == pytest.approx(sum(s["minutes"] for s in got["steps"]))
    lid = next(s for s in got["steps"] if s["id"] == "step-lid")
    assert lid["screw"] > 0 and lid["insert"] > 0      # the lid step drives the lug and handle screws into inserts


CLOSEUPS = """return Array.from(document.querySelectorAll('section.step')).map(s => {
  const close = s.querySelector('figure.closeup img');
  const fast = Array.from(s.querySelectorAll('h3')).filter(e => e.textContent === 'Fasteners')
      .flatMap(e => Array.from(e.nextElementSibling.querySelectorAll('li'))).map(li => li.textContent);
  return {id: s.id, close: close ? {src: close.getAttribute('src'), w: close.naturalWidth, complete: close.complete} : null,
          callouts: Array.from(s.querySelectorAll('.callout')).map(c => [Number(c.dataset.count), c.dataset.size]),
          fasteners: fast};
});"""


def test_closeups_and_screw_callouts_in_the_browser(docs_default, browser):
    """Every step that adds parts has a close-up, loaded; its callouts name each screw size the step drives
    with the count the step's fastener list gives; the close-up is framed on the new parts: the highlight
    colour covers more of it than of the whole-rig picture (measured on the PNGs)."""
    import cv2
    import numpy as np
    from docs.guide.pictures import HIGHLIGHT
    browser.get((docs_default / "assembly.html").as_uri())
    steps = browser.execute_script(CLOSEUPS)
    with_close = [s for s in steps if s["close"]]
    assert len(with_close) >= 10
    for s in with_close:
        assert s["close"]["complete"] and s["close"]["w"] == 960, s
        screws = {size: n for n, size in s["callouts"] if not size.startswith("insert")}
        listed = {}
        for text in s["fasteners"]:
            m = re.match(r"(\d+) x (M[\d.]+|1/4-20 UNC) x ([\d.]+) mm", text)
            if m:
                listed[f"{m.group(2)} x {float(m.group(3)):g}"] = listed.get(f"{m.group(2)} x {float(m.group(3)):g}", 0) + int(m.group(1))
        assert screws == listed, (s["id"], screws, listed)

    def blue_fraction(path):    # the highlight, lit: blue well above red and green
        b, g, r = np.moveaxis(cv2.imread(str(path), cv2.IMREAD_COLOR).astype(float) / 255, 2, 0)
        return float(np.mean((b > 0.4) & (b > r + 0.3) & (b > g + 0.15)))
    assert HIGHLIGHT[2] > HIGHLIGHT[0] + 0.3 and HIGHLIGHT[2] > HIGHLIGHT[1] + 0.15
    cores = next(s for s in with_close if s["id"] == "step-thermal_cores")
    full = docs_default / cores["close"]["src"].replace("_close", "")
    assert blue_fraction(docs_default / cores["close"]["src"]) > 1.5 * blue_fraction(full)


CABLE_PICTURES = """return Array.from(document.querySelectorAll('figure.cables')).map(f => ({
  step: f.closest('section').id, w: f.querySelector('img').naturalWidth, complete: f.querySelector('img').complete,
  cables: Array.from(f.querySelectorAll('.cable')).map(c => [c.dataset.route, Number(c.dataset.boughtMm)]),
}));"""


def test_cable_pictures_of_the_wiring_steps(docs_default, browser):
    """The steps that lay cables show them as routed, loaded in the browser, each cable at the length the
    BOM's cables table buys (read from bom.html)."""
    browser.get((docs_default / "assembly.html").as_uri())
    figs = {f["step"]: f for f in browser.execute_script(CABLE_PICTURES)}
    assert {"step-cables", "step-controls"} <= set(figs)
    assert {r for r, _ in figs["step-cables"]["cables"]} >= {"gmsl2", "sync_left", "sync_right", "usb_left", "usb_right", "dc_lead"}
    assert {r for r, _ in figs["step-controls"]["cables"]} == {"pigtail_left", "pigtail_right", "button_switch",
                                                              "button_switch_ground", "button_led", "button_led_ground"}
    html = (docs_default / "bom.html").read_text()
    bought = {m[0]: float(m[1]) for m in re.findall(r'id="cable-([a-z0-9-]+)" data-route-mm="[0-9.]+" data-bought-mm="([0-9.]+)"', html)}
    for f in figs.values():
        assert f["complete"] and f["w"] == 960, f
        for route, mm in f["cables"]:
            assert mm == bought[route.replace("_", "-")], route


# ------------------------------------------------------------------------------- printing: supports per part
SUPPORTS = """return {
  summary: document.querySelector('#supports-summary').textContent,
  rows: Array.from(document.querySelectorAll('#supports-table tbody tr')).map(r => ({
    part: r.id.replace('supports-', ''), ok: r.dataset.ok === 'true', cells: Array.from(r.cells).map(c => c.innerText),
    bridge: r.querySelector('.bridge') ? r.querySelector('.bridge').textContent : null,
    places: Array.from(r.querySelectorAll('li.place')).map(li => li.textContent), shown: r.getBoundingClientRect().height > 0})),
};"""


@pytest.fixture(scope="module")
def built_default():
    """The default rig's assembly, BOM and guide, in process (the docs_default site is built from the same)."""
    from bom.bom import build_bom
    from bom.catalogue import load_catalogue
    from cad.assembly import build
    from docs.guide.steps import load_guide
    from platform_tools.rig import load_rig
    rig = load_rig()
    asm = build(rig)
    bom = build_bom(asm, load_catalogue(rig, None))
    return asm, bom, load_guide(asm, bom)


def test_printing_page_shows_the_printability_check_per_part(docs_default, built_default, browser):
    """Each printed part's row, as the browser shows it, says what check "printable without supports"
    (cad/checks.py check_printable) found: its verdict and longest bridge, and the orientation it was
    measured in (cad PRINT_SETUPS)."""
    from cad.assembly import PRINT_SETUPS
    from cad.checks import check_printable
    asm = built_default[0]
    check = check_printable(asm)
    bridges = dict(re.findall(r"^(\w+): ok; .* longest bridge ([\d.]+) mm$", "\n".join(check.details), re.M))
    browser.get((docs_default / "printing.html").as_uri())
    got = browser.execute_script(SUPPORTS)
    rows = {r["part"]: r for r in got["rows"]}
    assert set(rows) == set(check.data) and len(rows) >= 10
    p = asm.rig.desc.printing.printer
    for pid, r in rows.items():
        assert r["shown"] and r["ok"] == (not check.data[pid]["failing"]), r
        rpy = ", ".join(f"{int(a)}" for a in PRINT_SETUPS[pid].rpy_deg)
        assert r["cells"][1].startswith(f"{rpy} deg: ") and PRINT_SETUPS[pid].why[:30] in r["cells"][1], r
        if r["bridge"] is not None:
            assert r["bridge"] == f"{bridges[pid]} mm" and f"limit {p.max_bridge_mm:g} mm" in r["cells"][2], r
        assert r["cells"][2].startswith("no supports") and not r["places"], r
    assert rows["case_lid"]["bridge"] == f"{bridges['case_lid']} mm" and float(bridges["case_lid"]) > 10
    assert got["summary"].startswith(f"Supports: none for any of the {len(rows)} printed parts")


def test_printing_page_names_where_supports_are_needed(docs_default, built_default, browser, tmp_path):
    """Given a check result with a part that fails (the ZED shelf turned upside down: its shelf then
    overhangs the bed), the page says "supports needed" for that part with the place the check measured."""
    import numpy as np
    from cad.checks import printed_meshes
    from cad.printability import analyse
    from docs.guide.site import page_context, render_page
    asm, bom, guide = built_default
    p = asm.rig.desc.printing.printer
    meshes = printed_meshes(asm)
    results = {pid: analyse(tri, p.max_overhang_deg, p.max_bridge_mm) for pid, tri in meshes.items()}
    flipped = meshes["zed_mount"] * np.array([1.0, -1.0, -1.0])          # 180 deg about x: a proper rotation
    flipped -= flipped.reshape(-1, 3).min(axis=0) - meshes["zed_mount"].reshape(-1, 3).min(axis=0)
    results["zed_mount"] = bad = analyse(flipped, p.max_overhang_deg, p.max_bridge_mm)
    assert bad.failing
    (tmp_path / "printing.html").write_text(render_page("printing.html", page_context(asm, bom, guide, results)))
    shutil.copy(docs_default / "style.css", tmp_path / "style.css")
    browser.get((tmp_path / "printing.html").as_uri())
    got = browser.execute_script(SUPPORTS)
    rows = {r["part"]: r for r in got["rows"]}
    zed = rows["zed_mount"]
    assert not zed["ok"] and zed["cells"][2].startswith("supports needed"), zed
    assert zed["places"] == [g.describe() for g in bad.failing] and "span" in zed["places"][0], zed
    assert all(r["ok"] for pid, r in rows.items() if pid != "zed_mount")
    assert got["summary"].startswith(f"Supports: supports needed for 1 of {len(rows)} parts (zed_mount)")
