#!/usr/bin/env bash
# Set up everything this repository needs on a Debian 12 machine, idempotently.
#
#   ./bootstrap.sh          (make demo / make test call it for you)
#
# 1. Debian packages: installed with apt-get when missing (as root), otherwise the
#    exact command to run is printed and the script stops.
# 2. .venv on /usr/bin/python3 with --system-site-packages, so that Debian's mrcal
#    and its numpy 1.x are the ones Python imports.
# 3. pip install -e '.[dev]' into it, redone only when pyproject.toml changes.
# 4. the export's numba kernels compiled ahead of time into an extension module for this
#    machine (platform_tools/dataset/kernels.py), redone only when their sources, numba or the
#    CPU change: the export's workers then start without importing numba. A failed build only
#    warns: the export uses numba's JIT instead (the same results, 0.3 s of CPU more per worker).
set -euo pipefail
cd "$(dirname "$0")"

# What each Debian package is for:
#   python3-venv            the virtualenv itself
#   python3-mrcal mrcal     camera calibration solver (Python API and command-line tools)
#   mrgingham               chessboard detector mrcal uses (compared against in bench/)
#   python3-numpy           numpy 1.x, the one mrcal is built against
#   python3-dev build-essential  compile wheels that have no binary for this Python
#   libgl1 libglib2.0-0     shared libraries the CadQuery/OCP wheels load
#   chromium chromium-driver  the real browser the generated web pages are tested in
#   docker-compose shellcheck  check the generated on-device files: shell entry scripts, and the
#                           compose file through `docker-compose config` (no Docker engine needed)
#   python3-cryptography openssl  SROS2 keys without ROS (rig-device sros2-keys), and the independent
#                           tool (openssl verify / smime -verify) the tests check those keys with
#   libzstd1 zstd           the export decompresses MCAP chunks with Debian's libzstd (built with zstd's
#                           assembly Huffman decoders: 1.2x python-zstandard's wheel, bench_dataset.py --zstd);
#                           the zstd tool writes a frame the tests read back
DEBIAN_PACKAGES=(
    python3-venv python3-mrcal mrcal mrgingham python3-numpy
    python3-dev build-essential libgl1 libglib2.0-0
    chromium chromium-driver
    shellcheck docker-compose
    python3-cryptography openssl
    libzstd1 zstd
)

say() { printf 'bootstrap: %s\n' "$*" >&2; }

missing=()
for p in "${DEBIAN_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
        missing+=("$p")
    fi
done
if ((${#missing[@]})); then
    cmd="apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
    if [[ $(id -u) -ne 0 ]]; then
        say "missing Debian packages: ${missing[*]}"
        say "run as root:  $cmd"
        exit 2
    fi
    say "installing Debian packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

VENV=.venv
if [[ ! -x $VENV/bin/python ]]; then
    say "creating $VENV on /usr/bin/python3 (with Debian's site packages)"
    /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi

stamp=$VENV/.installed
want=$(cat pyproject.toml bootstrap.sh | sha256sum | cut -d' ' -f1)
if [[ ! -f $stamp || $(cat "$stamp") != "$want" ]]; then
    say "installing the project and its Python dependencies into $VENV"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e '.[dev]'
    # CadQuery and nlopt without their declared dependencies: nlopt's wheels declare
    # numpy>=2 but run on Debian's numpy 1.24, which mrcal needs (see pyproject.toml).
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps \
        cadquery==2.8.0 nlopt==2.9.1
    # The pin in pyproject.toml keeps numpy < 2; check that mrcal really imports.
    "$VENV/bin/python" -c 'import mrcal, numpy, cv2, cadquery; assert numpy.__version__ < "2"' \
        || { say "mrcal does not import in $VENV (numpy $("$VENV/bin/python" -c 'import numpy; print(numpy.__version__)'))"; exit 1; }
    echo "$want" >"$stamp"
fi

if ! out=$("$VENV/bin/python" -m platform_tools.dataset.kernels build 2>&1); then
    say "warning: ${out##*$'\n'} (the export will use numba's JIT)"
elif [[ $out != *"already built"* ]]; then
    say "${out}"
fi
