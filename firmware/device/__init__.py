"""What runs on the Orin: the record button and its LED, the recorder state machine, the
`ros2 bag record` process, MCAP checks and recovery, pre-flight checks and the disk watchdog.

- ``gpio``          GPIO backends: Jetson.GPIO, files (tests across processes), memory
- ``button``        debounce, short and long presses;  ``led``  patterns and blink codes
- ``bagproc``       the recorder process and its backends (ros2; fake: platform_tools.sim.fake_recorder,
                    a workstation stand-in for tests); SIGINT, then escalation
- ``mcapcheck``     check an MCAP after a stop; recover one without summary
- ``storage``       mount points, free space, the disk watchdog
- ``preflight``     the checks before recording (and `rig-device doctor`); ``bosonprobe`` the Boson part
- ``ffc_status``    the FFC status of each frame, from its telemetry rows; ``ffc_node`` its ROS 2 node
- ``metadata``      recording.json per recording
- ``recorder``      the state machine and the button loop
"""
