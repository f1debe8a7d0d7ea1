"""A simulated rig: MCAP recordings with ROS 2 CDR messages, as the rig would write them, with
injected timing faults and a truth file listing them.

- ``msgs``      ROS 2 message definitions and dict builders
- ``timeline``  when each camera captured and what went wrong (jitter, offsets, drops, FFC, clock step)
- ``scenes``    the images: thermal from calibration.synth when present, a simple scene otherwise
- ``writer``    write the recording (MCAP + rosbag2 metadata.yaml + truth.json)
"""
