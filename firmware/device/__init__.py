"""What runs on the Orin: the record button and its LED, the recorder state machine, the
`ros2 bag record` process, MCAP checks and recovery, pre-flight checks and the disk watchdog.

- ``gpio``          GPIO backends: Jetson.GPIO, files (tests across processes), memory
- ``button``        debounce, short and long presses;  ``led``  patterns and blink codes
- ``bagproc``       the recorder process and its backends (ros2, fake); SIGINT, then escalation
- ``fake_recorder`` a stand-in for `ros2 bag record` that writes MCAP and misbehaves on request
- ``mcapcheck``     check an MCAP after a stop; recover one without summary
- ``storage``       mount points, free space, the disk watchdog
- ``preflight``     the checks before recording (and `platform_tools doctor`); ``bosonprobe`` the Boson part
- ``metadata``      recording.json per recording
- ``recorder``      the state machine and the button loop
"""
