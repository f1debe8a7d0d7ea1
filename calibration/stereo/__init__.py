"""The thermal stereo pair: the left-right pose solved with mrcal from board views both cameras saw,
seeded from the two mono models and the CAD pose between them; its rectification and epipolar error.

- :mod:`.pairs`: which files are one board pose (DIR/left + DIR/right, paired by name) and their corners;
- :mod:`.solve`: the pose (and optionally both lenses) with mrcal, and how far it is from the seed;
- :mod:`.rectify`: mrcal's rectified system and maps, and the rectified-row disparity of matched corners;
- :mod:`.fisheye_check`: for a Kannala-Brandt pair, OpenCV's fisheye stereo functions (stereoCalibrate,
  stereoRectify) beside ours on the same corners;
- :mod:`.outputs`: the files ``calibrate thermal-stereo`` writes, each read back before it is kept.
"""
from .pairs import StereoInputError, StereoObservations
from .solve import StereoSolution, solve_pair

__all__ = ["StereoInputError", "StereoObservations", "StereoSolution", "solve_pair"]
