"""The guide's power-chain text against the wiring: every part of the chain named in the wiring diagram's
order, and no step telling the builder to connect a part that a later step fits."""
from __future__ import annotations

import re

import pytest

from tests.bom.conftest import REPO

#: builds the CAD assembly in process (the quick loop leaves it to make test)
pytestmark = pytest.mark.slow

STEPS = REPO / "docs" / "assembly" / "steps.yaml"
#: the words the test reads each block of the wiring diagram's power chain by (its own, not the guide's)
WORDS = {"battery": "battery", "gland": "gland", "fuse": "fuse", "switch": "switch", "cutoff": "cut-off",
         "converter": "converter"}
#: the power step's note before the chain was computed (issue 16, G5)
OLD_NOTE = ('"Wire battery + -> fuse -> power switch -> converter input; converter output (12 V) -> the DC lead to the\n'
            '        Orin\'s DC jack once the Orin is in (the cables step). See the wiring page. Check polarity with the '
            'multimeter before the Orin is connected."')


@pytest.fixture(scope="module")
def built():
    from bom.bom import build_bom
    from bom.catalogue import load_catalogue
    from cad.assembly import build
    from platform_tools.rig import load_rig
    rig = load_rig()
    asm = build(rig)
    return asm, build_bom(asm, load_catalogue(rig, None))


def wiring_chain(asm) -> list[str]:
    """The wiring diagram's power wires followed from the battery to the converter (block ids)."""
    from cad.electrical import power_counts
    from docs.guide.wiring import wiring
    blocks, wires, _ = wiring(asm.rig, power_counts(asm))
    titles = {b.id: b.title for b in blocks}
    out, at = ["battery"], "battery"
    while "converter" not in titles[at].lower():
        at = next(w.b for w in wires if w.kind == "power" and w.a == at)
        out.append(at)
    return out


def block_of(element: str) -> str | None:
    """The chain block an element of a "A -> B -> C" sentence names: the word found first in it."""
    found = [(element.lower().find(w), b) for b, w in WORDS.items() if w in element.lower()]
    return min(found)[1] if found else None


def chain_problems(guide, asm) -> list[str]:
    """What is wrong with the guide's power chain: parsed from the rendered notes ("A -> B -> C" sentences
    with two arrows or more), the step fitting each part read from the steps' nodes."""
    from docs.guide.steps import power_chain
    order = wiring_chain(asm)
    nodes = {c.block: set(c.nodes) for c in power_chain(asm)}
    fitted = {b: next(s.number for s in guide.steps if set(s.nodes) & nodes[b]) for b in order}
    problems, sentences = [], 0
    for s in guide.steps:
        for note in s.notes:
            for sentence in re.split(r"(?<=[;.])\s+", note):
                if sentence.count(" -> ") < 2:
                    continue
                sentences += 1
                elements = [(block_of(e), e) for e in sentence.split(" -> ")]
                named = [b for b, _ in elements if b]
                if named != order:
                    problems.append(f"step {s.number}: names {named}, the wiring has {order}")
                for b, e in elements:
                    if b in fitted and fitted[b] > s.number and f"fitted in step {fitted[b]}" not in e:
                        problems.append(f"step {s.number}: connects the {b} ({e!r}), fitted in step {fitted[b]}")
                    if b in fitted and fitted[b] <= s.number and "fitted in step" in e:
                        problems.append(f"step {s.number}: leaves the {b} open, fitted already in step {fitted[b]}")
                # a part left open is connected, between its chain neighbours, in the step that fits it
                for b, e in elements:
                    m = re.search(r"fitted in step (\d+)", e)
                    if not m:
                        continue
                    k = order.index(b)
                    later = next(t for t in guide.steps if t.number == int(m.group(1)))
                    said = " ".join(later.notes).lower()
                    if not all(WORDS[x] in said for x in (b, order[k - 1], order[k + 1])) or "between" not in said:
                        problems.append(f"step {later.number} does not connect the {b} between the "
                                        f"{order[k - 1]} and the {order[k + 1]}")
    if not sentences:
        problems.append("no note wires the power chain")
    return problems


def test_the_chain_is_read_from_the_wiring(built):
    """power_chain follows the wiring diagram's power wires, each block's nodes being parts of its kind."""
    from docs.guide.steps import power_chain
    asm, _ = built
    chain = power_chain(asm)
    assert [c.block for c in chain] == wiring_chain(asm) == ["battery", "gland", "fuse", "switch", "cutoff", "converter"]
    for c in chain:
        kinds = {asm.rig.part(asm.node(n).part_id).kind.value for n in c.nodes}
        assert c.nodes and kinds == {"battery_adapter" if c.block == "battery" else c.block}, c


def test_guide_wires_the_chain_in_order_and_no_part_before_it_is_fitted(built):
    from docs.guide.steps import load_guide
    asm, bom = built
    guide = load_guide(asm, bom)
    assert chain_problems(guide, asm) == []
    power = next(s for s in guide.steps if s.id == "power")
    switch = next(s for s in guide.steps if "power_switch" in s.nodes)
    assert switch.number > power.number        # the switch goes into the lid later: left open in the power step
    assert f"[power switch: fitted in step {switch.number}, leave a lead from the fuse and one to the " \
           "under-voltage cut-off free for it]" in " ".join(power.notes)
    assert "connect the power switch between the fuse and the under-voltage cut-off" in " ".join(switch.notes)


def test_the_old_power_note_fails(built, tmp_path):
    """The note as it was (no cut-off, no gland, the switch wired before it is fitted) is caught."""
    from docs.guide.steps import load_guide
    asm, bom = built
    text = STEPS.read_text()
    new = re.search(r'"Wire the power chain.*?connected\."', text, re.S)
    assert new, "the power step's chain note is not found"
    old = tmp_path / "steps.yaml"
    old.write_text(text.replace(new.group(0), OLD_NOTE))
    problems = chain_problems(load_guide(asm, bom, old), asm)
    assert any("names ['battery', 'fuse', 'switch', 'converter']" in p for p in problems), problems
    assert any("connects the switch" in p for p in problems), problems


def test_chain_join_in_a_step_that_fits_no_chain_part_is_refused(built, tmp_path):
    """{{ chain.join }} in a step that fits none of the chain is a guide problem (exit 2), not empty text."""
    from docs.guide.steps import GuideError, load_guide
    asm, bom = built
    text = STEPS.read_text()
    assert '"Set the handle inserts in the lid' in text
    bad = tmp_path / "steps.yaml"
    bad.write_text(text.replace('"Set the handle inserts in the lid', '"{{ chain.join }}. Set the handle inserts in the lid'))
    with pytest.raises(GuideError) as exc:
        load_guide(asm, bom, bad)
    assert "chain.join: this step fits no part of the power chain" in str(exc.value)
