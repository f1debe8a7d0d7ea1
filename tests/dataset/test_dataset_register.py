"""Registration against truth: the simulated rig's box scene, rendered by ray casting with the rig's
nominal cameras (platform_tools.sim.geometry), registered with the export's own calibration path.

- every ZED pixel lands within 0.5 px of where its true 3D point projects in the thermal image;
- the registered image is where it should be: the registered 3D point of each valid thermal pixel
  projects within 0.5 px of that pixel;
- occluded points never overwrite nearer ones: the registered depth is never behind the surface
  the thermal camera truly sees;
- nothing is splatted from pixels without depth;
- numba and the plain numpy (np.add.at) version agree; the numba lens models agree with mrcal.
"""
from __future__ import annotations

import numpy as np
import pytest

mrcal = pytest.importorskip("mrcal")

from platform_tools.dataset.calib import at_recorded_size, load_calibration  # noqa: E402
from platform_tools.dataset.register import Registrar, register_numpy  # noqa: E402
from platform_tools.sim import geometry  # noqa: E402

TOL = 2.0                    # zbuffer tolerance, percent (the rig's default)


@pytest.fixture(scope="module")
def scene(rig):
    # the sizes the rig records: the ZED at HD1200 / zed_pub_downscale_factor (its depth too), the
    # Bosons at 640x512
    zspec = rig.camera_model(rig.desc.sensors.zed_x.camera_model)
    tspec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    down = rig.desc.on_device.zed_pub_downscale_factor
    ZED_SIZE = (int(zspec.width_px / down), int(zspec.height_px / down))
    THERMAL_SIZE = (tspec.width_px, tspec.height_px)
    boxes = geometry.boxes_at(geometry.SCENE, 0.7)
    zed = geometry.sim_camera(rig, "zed_x_left_optical", *ZED_SIZE)
    th = geometry.sim_camera(rig, "thermal_left_optical", *THERMAL_SIZE)
    zr = geometry.cast(zed, geometry.rays_rig(zed), boxes)
    tr = geometry.cast(th, geometry.rays_rig(th), boxes)
    depth = geometry.zed_depth_m(zr, geometry.SCENE)
    cal = load_calibration(rig)
    reg = Registrar(at_recorded_size("zed_x_left_optical", cal.cams["zed_x_left_optical"], ZED_SIZE, "test"),
                    at_recorded_size("thermal_left_optical", cal.cams["thermal_left_optical"], THERMAL_SIZE, "test"),
                    cal.rt_a_b("thermal_left_optical", "zed_x_left_optical"), TOL, min_coverage=0.5)
    return dict(boxes=boxes, zed=zed, th=th, zr=zr, tr=tr, depth=depth, reg=reg)


@pytest.mark.slow
def test_scene_has_occlusions_and_missing_depth(scene):
    d = scene["depth"]
    assert np.isnan(d).mean() > 0.2                            # sky: no depth
    assert len(np.unique(scene["zr"].which)) == 5             # four boxes and the sky


def test_every_point_lands_within_half_a_pixel_of_its_truth(scene):
    us, vs, zs = scene["reg"].points(scene["depth"])
    pts = scene["zr"].points_mm.reshape(-1, 3)
    q_true, z_true = geometry.project_rig(scene["th"], pts)
    landed = ~np.isnan(us)
    assert landed.sum() > 0.4 * landed.size
    err = np.hypot(us[landed] - q_true[landed, 0], vs[landed] - q_true[landed, 1])
    assert err.max() < 0.5, err.max()
    assert np.allclose(zs[landed], z_true[landed] / 1000.0, rtol=1e-5)


@pytest.mark.slow
def test_registered_image_lands_where_it_should(scene):
    """Register the true 3D points as the 'colour': each valid thermal pixel's registered point must
    project back onto that pixel (within 0.5 px) and lie on the surface the thermal camera sees."""
    reg, th = scene["reg"], scene["th"]
    res = reg.register(scene["depth"], scene["zr"].points_mm.astype(np.float64))
    assert res.mask.mean() > 0.4
    q, _ = geometry.project_rig(th, res.image.astype(np.float64)[res.mask])
    vv, uu = np.nonzero(res.mask)
    err = np.hypot(q[:, 0] - uu, q[:, 1] - vv)
    assert np.percentile(err, 99.5) < 0.5 and np.median(err) < 0.1, (np.median(err), np.percentile(err, 99.5))
    # everywhere the z-buffer's premise holds, all within 0.5 px: the pixel and its 8 neighbours valid,
    # on one box, and the true depth changing by less than the z-buffer tolerance across them (a
    # surface seen at a grazing angle changes faster: the near side of each pixel wins there, the
    # documented limit of a depth-relative z-buffer)
    z = np.nan_to_num(scene["tr"].z_m, nan=np.inf)
    which = scene["tr"].which
    interior = res.mask.copy()
    zmin, zmax = z.copy(), z.copy()
    for dv in (-1, 0, 1):
        for du in (-1, 0, 1):
            shifted = lambda a: np.roll(np.roll(a, dv, 0), du, 1)  # noqa: E731
            interior &= shifted(res.mask) & (shifted(which) == which)
            zmin, zmax = np.minimum(zmin, shifted(z)), np.maximum(zmax, shifted(z))
    with np.errstate(invalid="ignore"):                   # sky: inf - inf
        interior &= (zmax - zmin) <= zmin * TOL / 100
    assert interior.sum() > 0.8 * res.mask.sum()
    assert err[interior[res.mask]].max() < 0.5


@pytest.mark.slow
def test_occluded_points_never_overwrite_nearer_ones(scene):
    res = scene["reg"].register(scene["depth"], np.zeros(scene["depth"].shape, np.float32))
    truth = scene["tr"].z_m
    valid = res.mask & np.isfinite(truth)
    # never behind the surface the thermal camera sees (beyond the z-buffer tolerance)
    assert np.all(res.depth_m[valid] <= truth[valid] * (1 + TOL / 100) + 1e-6)
    # and on it nearly everywhere (in front of it only along silhouettes, by the splat's pixel)
    on = np.abs(res.depth_m[valid] - truth[valid]) <= truth[valid] * TOL / 100
    assert on.mean() > 0.97
    # the near box hides part of the wall and the walker from the thermal camera but not all of
    # it from the ZED: those ZED points land on near-box pixels and must lose there
    near = scene["boxes"].index(next(b for b in scene["boxes"] if b.name == "near"))
    on_near = valid & (scene["tr"].which == near)
    assert on_near.sum() > 20
    assert np.all(res.depth_m[on_near] < 1.5)


def test_no_splatting_without_depth(scene):
    reg, depth = scene["reg"], scene["depth"].copy()
    region = np.zeros(depth.shape, bool)
    region[200:400, 300:660] = True                      # a hole in the depth over boxes and wall
    share = reg.register(depth, region.astype(np.float64))
    depth[region] = np.nan
    res = reg.register(depth, np.ones(depth.shape, np.float32))
    only_from_hole = share.mask & (share.image[..., 0] > 0.999)
    assert only_from_hole.sum() > 50
    assert not res.mask[only_from_hole].any()
    assert not reg.register(np.full(depth.shape, np.nan, np.float32), depth).mask.any()
    assert not reg.register(np.zeros(depth.shape, np.float32), depth).mask.any()


@pytest.mark.slow
def test_numba_and_numpy_agree(scene):
    rgb = (np.random.default_rng(1).random((*scene["depth"].shape, 3)) * 255).astype(np.uint8)
    a = scene["reg"].register(scene["depth"], rgb)
    b = register_numpy(scene["reg"], scene["depth"], rgb)
    assert np.array_equal(a.mask, b.mask)
    np.testing.assert_allclose(a.image, b.image, atol=1e-3)
    np.testing.assert_allclose(np.nan_to_num(a.depth_m), np.nan_to_num(b.depth_m), atol=1e-5)


@pytest.mark.parametrize("lensmodel, extra", [
    ("LENSMODEL_PINHOLE", []), ("LENSMODEL_STEREOGRAPHIC", []),
    ("LENSMODEL_OPENCV8", [-0.3, 0.1, 1e-3, -5e-4, -0.02, 0.01, 0.02, -0.01]),
    ("LENSMODEL_OPENCV4", [-0.2, 0.05, 2e-3, 1e-3]),
    ("LENSMODEL_OPENCV12", [-0.2, 0.05, 1e-3, 1e-3, 0, 0, 0, 0, 1e-3, 0, 1e-3, 0])])   # via mrcal.project
def test_thermal_lens_models_project_as_mrcal(scene, lensmodel, extra):
    from platform_tools.rig.cameras import camera_model, imagersize
    th = scene["reg"].thermal
    cam = camera_model(lensmodel, np.concatenate([th.intrinsics()[1][:4], extra]), imagersize(th),
                       th.extrinsics_rt_fromref())
    reg = Registrar(scene["reg"].zed, cam, np.concatenate([mrcal.r_from_R(scene["reg"].R), scene["reg"].t]), TOL)
    us, vs, zs = reg.points(scene["depth"])
    ok = ~np.isnan(us)
    d = scene["depth"].ravel()[ok]
    p = np.concatenate([reg.rays.reshape(-1, 2)[ok] * d[:, None], d[:, None]], 1) @ reg.R.T + reg.t
    q = mrcal.project(p, *cam.intrinsics())
    assert ok.sum() > 1000
    np.testing.assert_allclose(np.stack([us[ok], vs[ok]], 1), q, atol=1e-6)


def test_register_u8_writes_the_pixels_of_the_float_path(scene):
    """The export's one-pass conversion (register_u8) against Result's numpy conversions, on the scene with its
    sky (no depth) and a patch pushed beyond 65.535 m (the uint16 mm clip)."""
    reg = scene["reg"]
    depth = scene["depth"].copy()
    h, w = depth.shape
    depth[h // 3:h // 3 + 40, w // 3:w // 3 + 40] = 80.0
    bgr = geometry.colour(scene["zr"], scene["boxes"], geometry.SCENE)
    a = reg.register(depth, bgr)
    b = reg.register_u8(depth, bgr)
    assert np.array_equal(b.image, a.image_u8())
    assert np.array_equal(b.mask, a.mask.astype(np.uint8) * 255)
    want_mm = np.clip(np.nan_to_num(a.depth_m * 1000.0, nan=0.0), 0, 65535).astype(np.uint16)
    assert np.array_equal(b.depth_mm, want_mm)
    assert (want_mm == 65535).sum() > 0 and (want_mm == 0).sum() > 0      # both clips exercised
    assert b.fraction == float(a.mask.mean())
    mono = reg.register_u8(depth, bgr[..., 1])                              # one channel: (h, w)
    assert mono.image.shape == a.mask.shape and np.array_equal(mono.image, a.image_u8()[..., 1])


def _splat_reference(uvz, src, h, w, tol):
    """The two passes of the splat (register_kernels._zbuffer, _blend_rows) as plain Python, point by point and
    corner by corner in the same order: the same sums to the bit."""
    zbuf = np.full((h, w), np.inf)
    packed = np.zeros((h, w, src.shape[1] + 2))
    corners = []
    for u, v, z in uvz:
        u0, v0 = int(np.floor(u)), int(np.floor(v))
        fu, fv = u - u0, v - v0
        corners.append([(u0 + du, v0 + dv, (fv if dv else 1.0 - fv) * (fu if du else 1.0 - fu), z)
                        for dv in (0, 1) for du in (0, 1)])
    for cs in corners:
        for uu, vv, wt, z in cs:
            if 0 <= vv < h and 0 <= uu < w and wt > 0.0 and z < zbuf[vv, uu]:
                zbuf[vv, uu] = z
    for j, cs in enumerate(corners):
        for uu, vv, wt, z in cs:
            if 0 <= vv < h and 0 <= uu < w and wt > 0.0 and z <= zbuf[vv, uu] * (1.0 + tol):
                packed[vv, uu, :-2] += wt * src[j].astype(np.float64)
                packed[vv, uu, -2] += wt
                packed[vv, uu, -1] += wt * z
    return zbuf, packed


@pytest.mark.parametrize("channels", [3, 1])
def test_splat_on_the_rim_and_on_whole_pixels_is_the_reference_to_the_bit(channels):
    """The splat's fast path for points whose four neighbours are inside and its path for the image's rim give what
    the plain two-pass loop gives, bit for bit: points anywhere in (-1, w) x (-1, h), on whole and half pixels (zero
    weights), on the last row and column, occluding one another (a z-buffer that differs from pixel to pixel, some
    points within its tolerance)."""
    from tests.dataset.test_dataset_speed_register import splat
    rng = np.random.default_rng(7)
    h, w, tol = 12, 16, 0.02
    uv = np.concatenate([rng.uniform([-1, -1], [w, h], (300, 2)),
                         rng.integers([-1, -1], [w, h], (60, 2)).astype(float),             # whole pixels
                         rng.integers([-1, -1], [w, h], (40, 2)) + 0.5,
                         [[w - 1, h - 1], [w - 1.0 + 1e-9, 0.0], [-1.0 + 1e-9, h - 1.0 + 1e-9], [0.0, 0.0]]])
    z = rng.uniform(1.0, 4.0, len(uv))                # each pixel's nearest differs from its neighbours'
    z[::3] = z[1::3][:len(z[::3])] * 1.01               # and some points within the tolerance of another
    uvz = np.ascontiguousarray(np.column_stack([uv, z]))
    src = rng.integers(0, 256, (len(uvz), channels)).astype(np.uint8)
    zbuf, packed = splat(uvz, np.arange(len(uvz)), src, h, w, tol)
    ref_z, ref_packed = _splat_reference(uvz, src, h, w, tol)
    assert np.array_equal(zbuf, ref_z) and np.array_equal(packed, ref_packed)
    assert (packed[..., -2] > 0).sum() > 0.8 * h * w           # the points cover the image, rim included


def test_the_ring_plan_holds_every_open_row_and_finalises_rows_no_later_point_reaches():
    """ring_plan on hand-made reaches: a row is final before ZED row r when no point of rows r.. reaches it; the ring
    holds the most rows open at once, as a power of two, never more than the image's; empty ZED rows (out_h, -1)
    change nothing; points above the image (-1) do not make a negative bound."""
    from platform_tools.dataset.register import ring_plan
    reach = np.array([[-1, 3], [2, 6], [12, 6], [5, 9], [7, 12]])
    reach[2] = [100, -1]                                    # a ZED row with no point in view
    final, rows = ring_plan(reach, 100)
    assert final.tolist() == [0, 2, 5, 5, 7] and final.dtype == np.int64 and final.flags.c_contiguous
    # open at once: row 0: -1..3 (5), row 1: 2..6 (5), row 2: 5..6, row 3: 5..9 (5), row 4: 7..12 (6) -> 8
    assert rows == 8
    assert ring_plan(np.array([[0, 60], [0, 61]]), 50)[1] == 64            # at most the image's power of two
    assert ring_plan(np.array([[5, 6]]), 10) == (ring_plan(np.array([[5, 6]]), 10)[0], 2)
    assert ring_plan(np.array([[10, -1], [10, -1]]), 10)[1] == 1             # nothing in view


@pytest.mark.parametrize("roll", [0.0, 0.5, np.pi / 2, np.pi])
def test_register_u8_rows_from_a_ring_are_the_plain_two_pass_reference(roll):
    """register_u8 converts each thermal row from a ring of rows as soon as no later point reaches it. Against the
    plain Python two-pass splat (_splat_reference, the whole image, no ring) and numpy's conversions, bit for bit, on
    small cameras rolled about the optical axis: at 0 the ZED rows reach narrow bands of thermal rows (a ring smaller
    than the image, which wraps), at 90 and 180 degrees they reach all of them (a ring of the whole image); a near box
    occludes a far wall, some depth is missing, some points fall outside."""
    from platform_tools.dataset.register import _finish, ring_plan
    zed = mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([40.0, 40.0, 23.5, 17.5])),
                            imagersize=np.array([48, 36]))
    th = mrcal.cameramodel(intrinsics=("LENSMODEL_STEREOGRAPHIC", np.array([30.0, 30.0, 19.5, 15.5])),
                           imagersize=np.array([40, 32]))
    reg = Registrar(zed, th, np.array([0.0, 0.0, roll, 0.05, 0.01, 0.0]), TOL, min_coverage=0.5)
    rng = np.random.default_rng(3)
    depth = np.full((36, 48), 4.0) + rng.uniform(0, 0.01, (36, 48))
    depth[10:22, 14:30] = 1.5                                # the near box
    depth[rng.random((36, 48)) < 0.05] = np.nan
    depth = depth.astype(np.float32)
    bgr = rng.integers(0, 256, (36, 48, 3), dtype=np.uint8)
    _, _, n, _, reach = reg._in_view(depth)
    rows = ring_plan(reach, 32)[1]
    assert (rows < 32) if roll == 0.0 else (rows == 32)
    u, v, z = reg.points(depth)
    ok = ~np.isnan(u)
    zbuf, sums = _splat_reference(np.column_stack([u[ok], v[ok], z[ok]]), bgr.reshape(-1, 3)[ok], 32, 40, reg.tol)
    want = _finish(sums[..., :3], sums[..., 3], sums[..., 4], reg.min_weight)
    got = reg.register_u8(depth, bgr)
    assert np.array_equal(got.image, want.image_u8()) and np.array_equal(got.mask, want.mask.astype(np.uint8) * 255)
    assert np.array_equal(got.depth_mm, np.clip(np.nan_to_num(want.depth_m * 1000.0, nan=0.0), 0, 65535)
                          .astype(np.uint16))
    assert 0.3 < got.fraction < 0.95 and n > 1000
    near = got.depth_mm[got.mask > 0]
    assert (near < 2000).any() and (near > 3500).any()     # both surfaces registered

