"""The tolerance stack-up (cad/tolerances.py): the analytic RSS against a Monte Carlo of exactly seated,
composed perturbed locations; a figure by hand; looser fits and printer tolerances widen it."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cad.datums import camera_locations
from cad.tolerances import contribution_matrix, monte_carlo, stack_up
from platform_tools.rig import load_rig

#: each test lays out the rig (a second or two; Monte Carlo tests longer): left to `make test`
pytestmark = pytest.mark.slow


def _locations(rig):
    from cad.layout import layout
    return camera_locations(layout(rig))


@pytest.fixture(scope="module")
def locations(rig):
    return _locations(rig)


@pytest.mark.slow
@pytest.mark.parametrize("camera,relative", [("zed_x", None), ("thermal_left", None), ("thermal_right", "zed_x")])
def test_the_rss_sigma_matches_a_monte_carlo_of_seated_parts(locations, camera, relative):
    u = stack_up(locations, camera, relative)
    mc = monte_carlo(locations, camera, relative, n=2500, seed=1)
    std = mc.std(axis=0)
    assert np.all(np.abs(std - u.sigma) <= 0.08 * np.array(u.sigma) + 1e-4), (std, u.sigma)
    assert np.all(np.abs(mc.mean(axis=0)) < 0.15 * np.array(u.sigma) + 1e-3)


@pytest.mark.slow
def test_no_uniform_draw_exceeds_the_worst_case(locations):
    for camera, relative in (("zed_x", None), ("thermal_left", "zed_x")):
        u = stack_up(locations, camera, relative)
        mc = monte_carlo(locations, camera, relative, n=2000, seed=2, distribution="uniform")
        worst = np.abs(mc).max(axis=0)
        assert np.all(worst <= np.array(u.worst) * 1.01 + 1e-6), (worst, u.worst)
        assert np.all(worst > 0.3 * np.array(u.worst))           # and the draws do reach towards it


def test_the_heat_sink_yaw_from_its_two_screws_is_the_hand_figure(rig, locations):
    # two screws s apart, each off by (play + printed hole + machined hole) at most: yaw = 2 e / s
    on_bar = locations["thermal_left"][1]
    assert on_bar.name == "heat_sink_left on thermal_mount"
    J, _ = contribution_matrix((on_bar,), on_bar.frame)
    e = (rig.desc.printing.holes["M3"].normal_mm - 3.0) / 2 + rig.desc.printing.printer.tolerance_mm + \
        rig.desc.enclosure.heat_sink.tolerance_mm
    heads = [j.head for j in _layout_joints(rig) if j.name.startswith("heat_sink_left_")]
    s = abs(heads[0][1] - heads[1][1])
    assert math.degrees(np.abs(J[5]).sum()) == pytest.approx(math.degrees(2 * e / s), rel=1e-9)


def _layout_joints(rig):
    from cad.layout import layout
    return layout(rig).joints


def _sigma(rig, camera="thermal_left"):
    return np.array(stack_up(_locations(rig), camera, "zed_x").sigma)


@pytest.mark.parametrize("override,axes", [
    ("printing.printer.tolerance_mm=0.4", [0, 1, 2, 5]),        # faces and holes land further off (tilts: layers)
    ("enclosure.heat_sink.bore_clearance_mm=0.3", [4, 5]),          # the Boson tilts in a looser bore
    ("printing.holes.M3.normal_mm=3.55", [0, 1, 5]),                # screws slide and turn in looser holes
])
def test_a_looser_fit_or_printer_tolerance_widens_the_prior(rig, override, axes):
    base = _sigma(rig)
    loose = _sigma(load_rig(None, [override]))
    assert np.all(loose >= base - 1e-12)
    assert np.all(loose[axes] > base[axes] * 1.05), (override, base, loose)


def test_the_prior_is_the_stack_up_in_optical_axes(rig):
    from calibration.extrinsics.prior import stack_up_priors
    pr = stack_up_priors(rig)
    assert set(pr) == {"thermal_left", "thermal_right"}
    body = np.array(stack_up(_locations(rig), "thermal_left", "zed_x").sigma)
    opt = pr["thermal_left"].sigma_optical
    # optical x right = body -y, y down = body -z, z forward = body x (translations mm, rotations rad)
    assert opt[[0, 1, 2]] == pytest.approx(body[[1, 2, 0]], rel=1e-9)
    assert np.degrees(opt[[3, 4, 5]]) == pytest.approx(body[[4, 5, 3]], rel=1e-9)
