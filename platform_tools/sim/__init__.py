"""A simulated rig: MCAP recordings with ROS 2 CDR messages, as the rig would write them, with
injected timing faults and a truth file listing them.

- ``msgs``      ROS 2 message definitions and dict builders
- ``timeline``  when each camera captured and what went wrong (jitter, offsets, drops, FFC, clock step)
- ``geometry``  the images: a box scene of known geometry ray-cast with the rig's nominal cameras
                (ZED colour and depth, thermal counts); the truth registration is tested against
- ``writer``    write the recording (MCAP + rosbag2 metadata.yaml + truth.json)
"""
