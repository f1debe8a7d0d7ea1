"""`rig-device record-service` (`platform_tools record-service` on a workstation): the button-driven
recorder that runs on the Orin."""
from __future__ import annotations

import argparse
import logging
import os
import signal
import threading
from pathlib import Path

from firmware.commands.doctor import add_preflight_options
from firmware.device.bagproc import backend_from_spec
from firmware.device.button import Button
from firmware.device.gpio import GpioError, open_gpio
from firmware.device.preflight import run_preflight
from firmware.device.recorder import ButtonLoop, Recorder
from platform_tools.rig.conventions import UserError, add_output_options, add_rig_options, rig_from_args

log = logging.getLogger("platform_tools.recorder")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record-service", help="the record button: start and stop recordings (runs on the Orin)",
                       description="Watch the record button and drive the recorder: a press runs the pre-flight "
                                   "and starts `ros2 bag record`, a press stops it (SIGINT, then escalation), "
                                   "checks every MCAP and recovers damaged ones; a long press stops a recording, "
                                   "or else runs the pre-flight and shows the result on the LED. SIGTERM stops "
                                   "a running recording cleanly, then exits. Faults are logged and written to "
                                   "events.jsonl in the output folder.",
                       epilog="LED: idle short blink every 2 s (power may be cut); recording on; stopping fast blink "
                              "(finishing: do not cut the power); error N blinks "
                              "(1 pre-flight, 2 recorder crashed, 3 disk full, 4 recorder did not start, "
                              "5 file damaged, 6 recorder hung).")
    add_rig_options(p)
    add_output_options(p, json_output=False)
    add_preflight_options(p)
    p.add_argument("--gpio", default="jetson", metavar="BACKEND",
                   help="'jetson' (Jetson.GPIO, default) or 'file:DIR' (pins as files, for tests)")
    p.add_argument("--recorder", default="ros2", metavar="BACKEND",
                   help="'ros2' (ros2 bag record, default), 'fake' or 'fake:MODE' (see fake_recorder)")
    p.add_argument("--calibration", metavar="FILE", type=Path,
                   help="calibration file whose hash goes into every recording's metadata")
    p.set_defaults(handler=cmd_record_service)


def cmd_record_service(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    button_cfg = rig.desc.recording.button
    active_low = rig.desc.on_device.button_active_low
    if args.calibration is not None and not args.calibration.is_file():
        raise UserError(f"--calibration {args.calibration}: no such file")
    try:
        backend = backend_from_spec(args.recorder)
        gpio = open_gpio(args.gpio, button_cfg.pin_numbering, 1 if active_low else 0)
    except (ValueError, GpioError) as exc:
        raise UserError(str(exc)) from None
    if args.no_boson:
        log.warning("--no-boson: recordings start without checking the cameras, trigger and sync mode")
    recorder = Recorder(rig, backend, output_dir=args.output_dir,
                        preflight=lambda: run_preflight(rig, args.output_dir, boson=not args.no_boson,
                                                        dev_dir=args.dev_dir, root=args.root),
                        calibration=args.calibration)
    stop = threading.Event()
    received: list[str] = []

    def on_signal(signum, frame):
        received.append(signal.Signals(signum).name)
        stop.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    loop = ButtonLoop(recorder, gpio, Button(button_cfg.bounce_ms / 1000.0, button_cfg.long_press_s, active_low),
                      button_cfg.gpio_pin, button_cfg.led_pin)
    # recordings a power loss interrupted are checked with the LED saying "do not cut the power"
    recorder.recover_interrupted_async()
    recorder.event("ready", pid=os.getpid(), recorder=backend.name)
    try:
        loop.run(stop)
    finally:
        reason = f"service stopped ({received[0] if received else 'exit'})"
        recorder.shutdown(reason)
        loop.gpio.write(button_cfg.led_pin, 0)
        gpio.close()
        recorder.event("exit", reason=reason)
    return 0
