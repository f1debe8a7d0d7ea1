"""FLIR Boson serial control: the FSLP protocol (pure, on bytes), typed commands, a pyserial
transport that survives re-enumeration, discovery by USB id and by serial number, the safe
read-diff-apply-verify-revert set-up of external sync, and an emulated Boson on a pseudo-terminal.

Module map:
- ``fslp``       framing, escaping, CRC, sequence numbers, stream decoder (no I/O)
- ``codes``      FLR_RESULT codes, one named exception class per code; the package's error types
- ``commands``   the typed command table (function id, request and reply layout, enums)
- ``transport``  the Transport protocol; the pyserial port: open, flush, read with deadlines, re-open
- ``loopback``   an in-memory Transport answering on bytes (tests of the client without a pty)
- ``client``     one camera: sequence numbers, reply matching, retries with back-off, reboot
- ``discovery``  cameras present (by-id links, pyserial port list, pyusb) and the rig's left/right
- ``operations`` identity and state, frame rate, FFC, factory defaults, raw commands; per camera, in parallel
- ``syncsetup``  the plan from the rig; read, diff, apply, verify, check the trigger, persist, revert
- ``transaction`` the set-up as one all-or-nothing transaction over the rig's cameras
- ``rigconfig``  which cameras a command works on (identified by their serial), and boson-config's run over them
- ``options``    the command-line options the boson-* commands share in either tool, and the fix doctor names
- ``telemetry``  the wire format of the telemetry rows below each image (FFC status, frame counters)
- ``emulator``   a stateful Boson on a pty with a by-id link, a simulated trigger and fault injection
"""
