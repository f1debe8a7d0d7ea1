"""What every part of calibration needs to know about a lens, below all of them (imports nothing else of
calibration): :mod:`.fit` (the nearest model of one kind to a lens of another, pixel grids), :mod:`.radial`
(OPENCV8 from a radial profile, linearly), :mod:`.kannala_brandt` (OpenCV's fisheye, and its one camera
value), :mod:`.compare` (the projection difference between a solved lens and the truth)."""
