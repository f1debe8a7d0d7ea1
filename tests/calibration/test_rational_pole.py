"""formats.conversions: the nearest OPENCV8 to a Kannala-Brandt lens is refitted on denser grids when the first fit
has a pole between its grid's points (a fit observed on 2026-12-05 in `calibrate thermal`'s end-to-end test on a
Zen 1 machine: numerator and denominator sharing a near root, no ray in a ring 65 px from the centre)."""
from __future__ import annotations

import numpy as np

from calibration.formats import conversions
from calibration.lens import kannala_brandt as kb
from calibration.lens.fit import LensFit
from calibration.lens.health import check_mrcal

#: the Kannala-Brandt solve of that run (as its .cameramodel's note gives it) and the OPENCV8 the fit returned
KB = np.array([408.357187, 407.940191, 321.829841, 253.785081, -0.0796434749, 0.00324889004, -0.0186287182,
               0.0281162268])
POLED = np.array([407.3474748, 406.9097801, 321.8275388, 253.7863099, -39.12867596, 13.84846422, -3.628426366e-06,
                  4.266706756e-06, 3.822178675, -38.73221249, -1.690348773, 12.12375011])
SIZE = (640, 512)


def test_the_observed_fit_has_no_ray_in_a_ring_near_the_centre():
    h = check_mrcal("LENSMODEL_OPENCV8", POLED, SIZE)
    assert not h.ok and h.round_trip_bad > 0


def test_a_fit_with_a_pole_is_refitted_healthy(monkeypatch):
    real = conversions.fit_lensmodel
    calls = []

    def fit(src, size, target, seed, **kw):
        calls.append(kw.get("n_width"))
        return LensFit(target, POLED.copy(), 0.008, 0.07) if len(calls) == 1 else real(src, size, target, seed, **kw)
    monkeypatch.setattr(conversions, "fit_lensmodel", fit)
    r = conversions.representation(kb.KannalaBrandt(KB, SIZE), "rational_polynomial")
    intrinsics = np.concatenate([[r.K[0, 0], r.K[1, 1], r.K[0, 2], r.K[1, 2]], r.D])
    assert calls[0] is None and calls[1] == conversions.REFIT_GRID_WIDTHS[0]
    assert check_mrcal("LENSMODEL_OPENCV8", intrinsics, SIZE).ok
    assert r.fit.rms_px < 0.05                                  # still the nearest OPENCV8: a close fit


def test_when_no_refit_is_healthy_the_first_fit_is_kept_for_the_health_report_to_name(monkeypatch):
    monkeypatch.setattr(conversions, "fit_lensmodel",
                        lambda src, size, target, seed, **kw: LensFit(target, POLED.copy(), 0.008, 0.07))
    r = conversions.representation(kb.KannalaBrandt(KB, SIZE), "rational_polynomial")
    assert np.array_equal(r.D, POLED[4:])
