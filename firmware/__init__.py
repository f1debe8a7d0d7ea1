"""Everything of the rig's on-device stack: the configuration rendered from the rig description, and the
Python the Orin runs. The device images install this package with platform_tools.rig and
platform_tools.boson, and nothing else of this repository.

- ``context``      every value the templates render, derived from the rig once
- ``render``       templates/ -> files; write them to a folder atomically, with a manifest
- ``checks``       validate what was rendered: compose, shellcheck, launch files, unit, udev rules, Dockerfiles
- ``launch_stub``  stand-ins for ROS 2's launch API, to import the rendered launch files without ROS
- ``device``       the runtime: recorder, record button and LED, pre-flight, MCAP checks, FFC status node
- ``commands``     the on-device commands (record-service, doctor); ``cli`` gathers them as `rig-device`
"""
