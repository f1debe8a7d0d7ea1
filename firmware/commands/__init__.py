"""The on-device commands, each a module with ``register(subparsers)``: ``record_service`` (the record
button's recorder) and ``doctor`` (the pre-flight checks). `rig-device` (firmware.cli) serves them on
the Orin, `platform_tools` (platform_tools.cli.main) on a workstation."""
