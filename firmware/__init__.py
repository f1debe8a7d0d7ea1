"""The on-device configuration (firmware/), rendered from the rig description, and its checks.

- ``context``  every value the templates render, derived from the rig once
- ``render``   templates -> files; write them to a folder atomically, with a manifest
- ``checks``   validate what was rendered: compose, shellcheck, launch files, unit, udev rules
"""
