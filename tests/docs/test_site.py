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
    assert html.count('<section class="step"') == len(list((docs_default / "img").glob("step_*.png")))


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
