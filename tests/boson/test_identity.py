"""Left and right from the serial number each camera answers over its serial link, not from the USB
serial string in its port's name: swapped, non-numeric, duplicate, unknown and missing serials, on
emulated cameras whose by-id links are made here (as udev would name them)."""
from __future__ import annotations

import json
import os

import pytest

from platform_tools.boson.emulator import BosonState, EmulatedBoson

from .conftest import FAST, LEFT, RIG_SERIALS, RIGHT


@pytest.fixture
def cameras(by_id, trigger):
    """cameras({usb_string: camera_serial}) -> emulated cameras with by-id links under those names."""
    started = []

    def make(names: dict[str, int]):
        emus = {}
        for usb, sn in names.items():
            emu = EmulatedBoson(BosonState(sn, trigger=trigger), by_id_dir=None, seed=sn).start()
            os.symlink(emu.path, by_id / f"usb-FLIR_Boson_{usb}-if00")
            started.append(emu)
            emus[usb] = emu
        return emus
    yield make
    for emu in started:
        emu.stop()


def config(cli, *extra):
    code, out, err = cli("boson-config", "--slave", *RIG_SERIALS, *FAST, "--json", *extra)
    return code, (json.loads(out) if out.strip() else None), err


def test_swapped_usb_strings_are_seen_and_each_camera_found_by_its_own_serial(cli, cameras, by_id):
    emus = cameras({str(RIGHT): LEFT, str(LEFT): RIGHT})      # each link names the other camera
    code, doc, err = config(cli)
    assert code == 0, err
    cams = {c["label"]: c for c in doc["cameras"]}
    assert cams["left"]["serial"] == LEFT and cams["left"]["port"] == str(by_id / f"usb-FLIR_Boson_{RIGHT}-if00")
    assert cams["right"]["port"] == str(by_id / f"usb-FLIR_Boson_{LEFT}-if00")
    assert err.count("USB serial says") == 2 and f"camera answers SN {LEFT}" in err
    assert all(e.state.settings["ext_sync_mode"] == 2 for e in emus.values())


def test_a_non_numeric_usb_string_is_identified_by_asking(cli, cameras):
    cameras({"ABC-1": LEFT, str(RIGHT): RIGHT})
    code, doc, err = config(cli)
    assert code == 0, err
    assert {c["label"]: c["serial"] for c in doc["cameras"]} == {"left": LEFT, "right": RIGHT}


def test_two_ports_answering_one_serial_are_refused_naming_both(cli, cameras):
    emus = cameras({"1": LEFT, "2": LEFT})
    code, doc, err = config(cli)
    assert code == 2 and f"SN {LEFT} is answered on 2 ports" in err
    assert "usb-FLIR_Boson_1-if00" in err and "usb-FLIR_Boson_2-if00" in err
    assert all(e.state.settings["ext_sync_mode"] == 0 for e in emus.values())


def test_a_missing_rig_camera_names_what_each_port_answered(cli, cameras):
    emus = cameras({str(LEFT): LEFT, "77": 77777})
    code, _, err = config(cli)
    assert code == 2 and f"right camera (SN {RIGHT}) not found" in err
    assert "usb-FLIR_Boson_77-if00 (USB serial 77) answers SN 77777" in err
    assert all(e.state.settings["ext_sync_mode"] == 0 for e in emus.values())


def test_an_unknown_third_camera_is_left_alone_with_a_warning(cli, cameras):
    emus = cameras({str(LEFT): LEFT, str(RIGHT): RIGHT, "55555": 55555})
    code, doc, err = config(cli)
    assert code == 0 and len(doc["cameras"]) == 2
    assert "holds SN 55555, which the rig does not name" in err
    assert emus["55555"].state.settings["ext_sync_mode"] == 0 and emus[str(LEFT)].state.settings["ext_sync_mode"] == 2
