#!/usr/bin/env bash
# Installs a real C++ YARP (3.5, PyPI's yarp-middleware, built from source by pip) into
# .venv-yarp/ for the live interoperability tests. The first build takes ~8 minutes on
# 2 cores; pip caches the built wheel (~/.cache/pip/wheels), so later installs take seconds.
# Prints the venv's bin directory on success.
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=${YARP_CPP_VENV:-$PWD/.venv-yarp}
if [[ -x $venv/bin/yarpserver ]]; then echo "$venv/bin"; exit 0; fi
if ! command -v swig >/dev/null || [[ ! -e /usr/include/ace/ACE.h ]]; then
    if [[ $(id -u) == 0 ]]; then
        (apt-get install -y swig libace-dev || { apt-get update && apt-get install -y swig libace-dev; }) >&2
    else
        echo "install-cpp-yarp: swig and libace-dev are required" >&2; exit 1
    fi
fi
# The 2021 sources need these on a current toolchain (see ../shared/cpp-yarp-peer.md).
export CMAKE_POLICY_VERSION_MINIMUM=3.5
export CXXFLAGS="-include utility -include cstdint -include limits -include iterator \
 -include algorithm -include memory -include string -include cstring -include mutex \
 -include functional -include stdexcept -include array"
python3 -m venv "$venv" >&2
"$venv/bin/pip" install -q yarp-middleware==3.5.0 >&2
echo "$venv/bin"
