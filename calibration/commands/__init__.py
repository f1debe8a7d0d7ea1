"""The `calibrate` subcommands, one module each (parse, call, print); `calibration.cli` gathers them."""
