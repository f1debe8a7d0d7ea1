"""Truth lenses of other families than the solver's (calibration/synth/truth_lens.py and friends),
each checked against a reference that does not share its code: cv2.fisheye for Kannala-Brandt,
cv2.projectPoints for the published plumb_bob Boson, the closed form and mrcal for stereographic;
the truth files read back by those tools; the renderer's corners against the rendered pixels."""
from __future__ import annotations

import dataclasses
import json
import math

import cv2
import mrcal
import numpy as np
import pytest

from calibration.synth import render_dataset
from calibration.synth.agc import agc8
from calibration.synth.board import Board
from calibration.synth.difficulty import level
from calibration.synth.poses import sample_view
from calibration.synth.render import Look, board_layer
from calibration.synth.truth_families import PUBLISHED_BOSON, SENSOR_SIZES, truth_lens
from calibration.synth.truth_files import write_truth_files

FOREIGN = ("kannala-brandt", "stereographic", "boson-published")


def _rays(lens, n=400, seed=1):
    """Unit rays (n, 3) spread over the lens' field up to the image corners' angle."""
    rng = np.random.default_rng(seed)
    W, H = lens.size
    q = rng.uniform([-0.5, -0.5], [W - 0.5, H - 0.5], size=(n, 2))
    q[:4] = [[-0.5, -0.5], [W - 0.5, -0.5], [-0.5, H - 0.5], [W - 0.5, H - 0.5]]
    th = np.arccos(lens.unproject(q)[:, 2])
    phi = rng.uniform(0, 2 * math.pi, n)
    return np.stack([np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi), np.cos(th)], axis=-1)


def test_kannala_brandt_is_opencv_fisheye():
    lens = truth_lens("kannala-brandt")
    v = _rays(lens)
    K = np.array([[lens.fx, 0, lens.cx], [0, lens.fy, lens.cy], [0, 0, 1.0]])
    ref, _ = cv2.fisheye.projectPoints(v.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, np.array(lens.coeffs))
    assert np.abs(lens.project(v) - ref.reshape(-1, 2)).max() < 1e-6
    # and it is not the solver's family: the nominal OPENCV8 lens is pixels away at the corners
    ref8 = mrcal.project(v, *truth_lens("opencv8").intrinsics())
    assert np.abs(lens.project(v) - ref8).max() > 5.0


def test_published_boson_is_opencv_plumb_bob():
    lens = truth_lens("boson-published")
    assert (lens.fx, lens.fy, lens.cx, lens.cy) == (PUBLISHED_BOSON["fx"], PUBLISHED_BOSON["fy"],
                                                     PUBLISHED_BOSON["cx"], PUBLISHED_BOSON["cy"])
    v = _rays(lens)
    K = np.array([[lens.fx, 0, lens.cx], [0, lens.fy, lens.cy], [0, 0, 1.0]])
    k1, k2, k3 = lens.coeffs
    ref, _ = cv2.projectPoints(v, np.zeros(3), np.zeros(3), K, np.array([k1, k2, 0, 0, k3]))
    assert np.abs(lens.project(v) - ref.reshape(-1, 2)).max() < 1e-6


def test_stereographic_is_the_closed_form():
    lens = truth_lens("stereographic")
    v = _rays(lens)
    th = np.arccos(v[:, 2])
    phi = np.arctan2(v[:, 1], v[:, 0])
    r = 2 * np.tan(th / 2)
    ref = np.stack([lens.cx + lens.fx * r * np.cos(phi), lens.cy + lens.fy * r * np.sin(phi)], axis=-1)
    assert np.abs(lens.project(v) - ref).max() < 1e-9
    # the half-width sits at half the rig's 95 deg HFoV
    a = lens.unproject(np.array([[-0.5, lens.cy], [lens.size[0] - 0.5, lens.cy]]))
    assert math.degrees(math.atan2(-a[0, 0], a[0, 2]) + math.atan2(a[1, 0], a[1, 2])) == pytest.approx(95, abs=0.5)


@pytest.mark.parametrize("family", FOREIGN)
def test_unprojection_round_trips_over_the_whole_image(family):
    lens = truth_lens(family)
    W, H = lens.size
    q = np.stack(np.meshgrid(np.linspace(-0.5, W - 0.5, 81), np.linspace(-0.5, H - 0.5, 65)), axis=-1)
    v = lens.unproject(q)
    assert np.allclose(np.linalg.norm(v, axis=-1), 1.0, atol=1e-12)
    assert np.abs(lens.project(v) - q).max() < 1e-8
    # and the other way: rays out to the corners' angle come back as the same rays
    r = _rays(lens)
    assert np.abs(lens.unproject(lens.project(r)) - r).max() < 1e-10


@pytest.mark.parametrize("family", FOREIGN)
def test_truth_files_are_read_by_independent_tools(family, tmp_path):
    lens = truth_lens(family)
    names = write_truth_files(tmp_path, lens, "test")
    table = np.load(tmp_path / "truth_table.npz")
    q, v = table["q"], table["v"]
    W, H = lens.size
    assert q.shape[-1] == 2 and q[0, 0].tolist() == [-0.5, -0.5] and q[-1, -1].tolist() == [W - 0.5, H - 0.5]
    assert np.isfinite(v).all()
    rays = v.reshape(-1, 3)
    if family == "kannala-brandt":
        assert "truth_fisheye.yaml" in names and "truth.cameramodel" not in names
        fs = cv2.FileStorage(str(tmp_path / "truth_fisheye.yaml"), cv2.FILE_STORAGE_READ)
        K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
        assert (int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real())) == (W, H)
        ref, _ = cv2.fisheye.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
    else:
        m = mrcal.cameramodel(str(tmp_path / "truth.cameramodel"))
        assert tuple(m.imagersize()) == (W, H)
        ref = mrcal.project(rays, *m.intrinsics())
    assert np.abs(ref.reshape(-1, 2) - q.reshape(-1, 2)).max() < 1e-6
    if family == "boson-published":
        text = (tmp_path / "truth_camera_info.yaml").read_text()
        assert "distortion_model: plumb_bob" in text and "-0.3565" in text


@pytest.mark.slow
@pytest.mark.parametrize("size", SENSOR_SIZES)
@pytest.mark.parametrize("family", FOREIGN)
def test_other_sensor_sizes_keep_the_field_of_view(family, size):
    lens = truth_lens(family, size)
    native = truth_lens(family)
    assert lens.size == size
    W, H = size
    a = lens.unproject(np.array([[-0.5, lens.cy], [W - 0.5, lens.cy]]))
    b = native.unproject(np.array([[-0.5, native.cy], [639.5, native.cy]]))

    def hfov(x):
        return math.degrees(math.atan2(-x[0, 0], x[0, 2]) + math.atan2(x[1, 0], x[1, 2]))
    assert hfov(a) == pytest.approx(hfov(b), abs=0.5)


def _symmetric_centre(img: np.ndarray, q0: np.ndarray, half: float) -> np.ndarray:
    """The point about which ``img`` (H, W) is most point-symmetric near ``q0`` (2,): an X-corner of a
    checker is point-symmetric, so this finds it from the pixels alone (no detector involved)."""
    from scipy.optimize import least_squares
    d = np.stack(np.meshgrid(np.linspace(-half, half, 9), np.linspace(-half, half, 9)), axis=-1).reshape(-1, 2)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 0.5]
    img = img.astype(np.float32)

    def sample(p):
        m = p.astype(np.float32).reshape(1, -1, 2)
        return cv2.remap(img, m[..., 0], m[..., 1], cv2.INTER_CUBIC).ravel()

    sol = least_squares(lambda c: sample(c + d) - sample(c - d), q0, diff_step=1e-3)
    return sol.x


@pytest.mark.slow
@pytest.mark.parametrize("family", FOREIGN)
def test_rendered_corners_land_where_the_truth_projects_them(family):
    lens = truth_lens(family)
    diff = dataclasses.replace(level("easy"), board_gradient=0.0, min_square_px=25.0)
    board = Board(6, 5, 0.05)
    view = sample_view(np.random.default_rng(4), lens, board, diff)
    look = Look(contrast_k=10.0, spread_m=0.0003, polarity=1.0, board_offset_k=6.0, blur_px=0.0,
                reflection=None, occluded=False)
    _, temp = board_layer(lens, board, view, look, diff)
    temp = cv2.GaussianBlur(temp, (0, 0), 1.0)     # smooth the pixel steps for the symmetry fit
    # the true corners as the family's independent reference projects them (cv2 / closed form)
    p = board.corners() @ view.R.T + view.t
    q_truth = lens.project(p)
    assert np.abs(q_truth - view.corners_px).max() < 1e-9
    inner = [k for k in range(board.n) if 0 < k % board.width < board.width - 1 and 0 < k // board.width < board.height - 1]
    found = np.array([_symmetric_centre(temp, q_truth[k] + [0.3, -0.2], 3.0) for k in inner])
    err = np.linalg.norm(found - q_truth[inner], axis=1)
    # what is left is the symmetry fit's own curvature term (0.01-0.02 px, zero mean), not the renderer
    assert np.median(err) < 0.025 and err.max() < 0.05
    # a lens of another family would put them pixels away on the same pose: the check can fail
    other = truth_lens("opencv8" if family != "opencv8" else "kannala-brandt")
    q_other = mrcal.project(p, *other.intrinsics())
    assert np.linalg.norm(found - q_other[inner], axis=1).max() > 0.5


@pytest.mark.slow
def test_render_dataset_through_a_foreign_lens_writes_its_truth(tmp_path):
    lens = truth_lens("kannala-brandt", (320, 256))
    truth = render_dataset(tmp_path / "s", n=1, difficulty="real", board=(6, 5), square=0.05, seed=3, lens=lens,
                           show_progress=False)
    files = sorted(p.name for p in (tmp_path / "s").iterdir())
    assert files == ["000.png", "truth.json", "truth_fisheye.yaml", "truth_table.npz"]
    assert truth["lensmodel"] == "kannala-brandt" and truth["imagersize"] == [320, 256]
    assert json.loads((tmp_path / "s" / "truth.json").read_text())["truth_lens"]["family"] == "kannala-brandt"
    img = cv2.imread(str(tmp_path / "s" / "000.png"), cv2.IMREAD_UNCHANGED)
    assert img.dtype == np.uint16 and img.shape == (256, 320)


def test_agc8_is_monotonic_full_range_and_equalises():
    rng = np.random.default_rng(0)
    frame = rng.normal(7500, 3, size=(128, 160))                # background: a few counts of noise
    frame[40:80, 50:110] += np.where((np.arange(60) // 10) % 2 == 0, 200.0, 0.0)[None, :]   # a board
    frame[0:4, 0:4] = 12000                                     # a hot object
    frame = np.rint(frame).astype(np.uint16)
    out = agc8(frame)
    assert out.dtype == np.uint8 and out.min() == 0 and out.max() == 255
    order = np.argsort(frame.ravel(), kind="stable")
    assert np.all(np.diff(out.ravel()[order].astype(int)) >= 0)
    # the board's two levels are far apart, although a linear stretch would put them 4 grey levels apart
    board = out[40:80, 50:110]
    hot, cold = board[:, :10].mean(), board[:, 10:20].mean()
    assert hot - cold > 40
