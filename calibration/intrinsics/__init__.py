"""Thermal intrinsics: corner observations in (:mod:`.observations`), a solved lens out.

- :mod:`.mrcal_solver`: mrcal in-process (OPENCV8 or SPLINED_STEREOGRAPHIC, :mod:`.lensmodels`);
- :mod:`.opencv_solver`: cv2.fisheye (Kannala-Brandt, :mod:`.kannala_brandt`);
- :mod:`.lensfit`: the nearest model of one kind to a lens of another;
- :mod:`.synthetic_corners`: observations through a known lens, for tests and the bench;
- :mod:`.outputs`: every file ``calibrate thermal`` writes.
"""
from .mrcal_solver import Solution, SolveError
from .observations import BoardObservations, from_detections

__all__ = ["BoardObservations", "from_detections", "Solution", "SolveError"]
