"""A stand-in for a learned-stereo plug-in (``--depth tests.dataset.stereo_standin:constant``): the documented
signature, an answer the tests can recognise (every pixel at 3 m, the left half of the image not confident)."""
import numpy as np

DEPTH_M = 3.0


def constant(left, right, calib):
    assert left.shape == right.shape and left.shape[:2] == (calib.size[1], calib.size[0])
    depth = np.full(left.shape[:2], DEPTH_M, np.float32)
    conf = np.ones(left.shape[:2], np.float32)
    conf[:, : left.shape[1] // 2] = 0.0
    return depth, conf


def wrong_shape(left, right, calib):
    return np.zeros((2, 2)), np.zeros((2, 2))
