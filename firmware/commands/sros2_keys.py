"""`rig-device sros2-keys --out DIR`: the SROS2 keystore and one enclave per ROS service of the rendered
stack (`firmware/sros2.py`), for `on_device.sros2_enclaves`. Never overwrites an existing keystore."""
from __future__ import annotations

import argparse
from pathlib import Path

from firmware import sros2
from firmware.context import KEYSTORE_DIR, enclaves
from platform_tools.rig import atomic
from platform_tools.rig.conventions import UserError, add_output_options, add_rig_options, print_json, rig_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sros2-keys", help="create the SROS2 keystore and the enclaves of the rig's ROS services",
                       description="Create an SROS2 keystore with one enclave per compose service that runs ROS 2 "
                                   "(the names compose.yaml sets as ROS_SECURITY_ENCLAVE_OVERRIDE), for the rig's "
                                   "domain. Uses `ros2 security create_keystore` / `create_enclave` when `ros2` is "
                                   "on PATH, else writes the same layout with the cryptography library. The folder "
                                   "appears whole or not at all; an existing one is never touched.",
                       epilog="Exit 0 when the keystore was written, 2 on bad input (the folder exists, a tool "
                              "failed or is missing). On the Orin: --out <install_dir>/keystore (compose mounts "
                              "it read-only at /keystore).")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--out", metavar="DIR", type=Path,
                   help=f"the keystore folder to create (default: on_device.install_dir/{KEYSTORE_DIR})")
    p.set_defaults(handler=cmd_sros2_keys)


def cmd_sros2_keys(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    out = args.out or Path(rig.desc.on_device.install_dir) / KEYSTORE_DIR
    if out.exists() or out.is_symlink():
        raise UserError(f"{out}: already exists; a keystore is never overwritten (move it away to make a new one)")
    names = enclaves(rig)
    domain = rig.desc.on_device.ros_domain_id
    try:
        with atomic.OutputDir(out) as stage:
            tool = sros2.generate(stage, names.values(), domain)
    except sros2.KeystoreError as exc:
        raise UserError(f"{out}: {exc}") from None
    doc = {"keystore": str(out), "tool": tool, "domain_id": domain, "enclaves": names}
    if args.json:
        print_json(doc)
    elif not args.quiet:
        print(f"{out}: keystore ({tool}), domain {domain}")
        for service, name in names.items():
            print(f"  {name:22s} {service}")
        if not rig.desc.on_device.sros2_enclaves:
            print("note: on_device.sros2_enclaves is false: render with it true for the services to use these keys")
    return 0
