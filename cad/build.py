"""`python cad/build.py`: build, export and check the rig's CAD model from config/rig.yaml.

    python cad/build.py export STEP|STL|GLB|SVG|PNG|all [--out DIR] [--set key=value ...]
    python cad/build.py check [--report FILE] [--json]
    python cad/build.py params [--json]
    python cad/build.py bom [--out DIR]     (bill of materials, bom/cli.py)
    python cad/build.py docs [--out DIR]    (assembly guide, BOM, wiring, printing pages; docs/guide/cli.py)

Exit codes: 0 ok, 1 a check failed, 2 bad input (a bad --set, an impossible design, an unwritable
output folder, an unknown format).

A shim: it only gathers the commands of cad/cli.py, bom/cli.py and docs/guide/cli.py into one tool
(the one module of cad/ allowed to reach bom and docs.guide, which stand on cad).
"""
from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):
    # `python cad/build.py` puts cad/ (not the checkout) first on sys.path; the packages it gathers
    # (cad, bom, docs, platform_tools) are top-level folders of the checkout, so add the checkout.
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from platform_tools.rig.conventions import dispatch, tool_parser  # noqa: E402


def build_parser():
    from bom import cli as bom_cli
    from cad import cli as cad_cli
    from docs.guide import cli as docs_cli
    return tool_parser("cad/build.py", __doc__.split("\n\n")[0], [cad_cli, bom_cli, docs_cli])


def main(argv=None) -> int:
    return dispatch(build_parser(), argv)


if __name__ == "__main__":
    raise SystemExit(main())
