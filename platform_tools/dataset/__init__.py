"""From recordings to a dataset (issue 9).

- ``recording``  open a recording (rosbag2 folder / MCAP files), index its streams by header stamp
- ``sync``       sync analysis: intervals, drops, clock steps, FFC periods, pairing residuals, verdict
- ``svgplot``    the sync plots, as SVG written here (no plotting library needed)
- ``thermal8``   16-bit raw thermal to 8-bit exactly as the paper (FIReStereo's pipeline)
- ``calib``      the export's calibration: mrcal camera models (nominal from the rig, or calibrated
                 .cameramodel files) at the recorded image sizes
- ``register``   RGB into a thermal view from depth: z-buffer, bilinear splatting, validity mask
- ``register_kernels``  its numba loops (imported only to compile them)
- ``kernels``    the compiled kernels: an extension built ahead of time for this machine, else numba's JIT
- ``pairing``    four-camera pairing, FFC filtering, sampling at a rate
- ``decode``     a recording's image messages to numpy arrays
- ``chunk``      one unit of the export's work: decode, convert, register, write a chunk of samples
- ``engines``    where the chunks run: inline, on a process pool or on a Dask cluster
- ``export``     the resumable export: plan the chunks, the manifest and resume, the index
"""
