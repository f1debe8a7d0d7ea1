"""Thermal intrinsics: corner observations in (:mod:`.observations`), a solved lens out.

- :mod:`.mrcal_solver`: mrcal in-process (OPENCV8 or SPLINED_STEREOGRAPHIC, :mod:`.lensmodels`);
- :mod:`.opencv_solver`: cv2.fisheye (Kannala-Brandt, :mod:`calibration.lens.kannala_brandt`);
- :mod:`.crossval`: the two halves' disagreement; :mod:`.sensitivity`: first-order bias of a solve;
- :mod:`.model_choice`: the default lens model, chosen by how well each candidate predicts held-out views;
- :mod:`.circle_bias`: a circle grid's centroid bias, iterated out of a solve (warm re-solves:
  ``mrcal_solver.resolve``, ``opencv_solver.resolve``);
- :mod:`.synthetic_corners`: observations through a known lens, for tests and the bench;
- :mod:`.quiet`: mrcal's C-level stderr chatter kept off the terminal.

Lens fitting lives in :mod:`calibration.lens`; every file ``calibrate thermal`` writes in
:mod:`calibration.thermal`.
"""
from .mrcal_solver import Solution, SolveError
from .observations import BoardObservations, from_detections

__all__ = ["BoardObservations", "from_detections", "Solution", "SolveError"]
