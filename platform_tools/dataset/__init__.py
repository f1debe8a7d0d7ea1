"""From recordings to a dataset (issue 9).

- ``recording``  open a recording (rosbag2 folder / MCAP files), index its streams by header stamp
- ``sync``       sync analysis: intervals, drops, clock steps, FFC periods, pairing residuals, verdict
- ``svgplot``    the sync plots, as SVG written here (no plotting library needed)
- ``thermal8``   16-bit raw thermal to 8-bit exactly as the paper (FIReStereo's pipeline)
- ``calib``      camera models for the export (nominal from the rig, or calibrated .cameramodel files)
- ``register``   RGB into a thermal view from depth: z-buffer, bilinear splatting, validity mask
- ``pairing``    four-camera pairing, FFC filtering, sampling at a rate
- ``export``     the resumable export, run inline, on a process pool or on a Dask cluster
"""
