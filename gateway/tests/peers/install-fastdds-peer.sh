#!/usr/bin/env bash
# Builds fastdds_secure_peer.cpp (a secured ROS 2 String node on Debian's Fast DDS, which
# has DDS Security; PyPI's has not) once, cached by a stamp of its source and of the
# libfastrtps-dev version; prints the binary's path. Needs libfastrtps-dev (.ci/run installs it).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
src=$here/fastdds_secure_peer.cpp
version=$(dpkg-query -W -f='${Version}' libfastrtps-dev 2>/dev/null || true)
if [[ -z $version || ! -f /usr/include/fastdds/dds/domain/DomainParticipant.hpp ]]; then
    echo "install-fastdds-peer.sh: Debian's libfastrtps-dev is not installed (apt-get install libfastrtps-dev)" >&2
    exit 1
fi
stamp=$( (cat "$src"; echo "$version") | sha256sum | cut -c1-16)
out=${YARP_RS_CACHE:-$HOME/.cache/yarp-rs}/fastdds-peer/$stamp/fastdds_secure_peer
if [[ ! -x $out ]]; then
    mkdir -p "$(dirname "$out")"
    g++ -std=c++17 -O1 -o "$out.tmp" "$src" -lfastrtps -lfastcdr
    mv "$out.tmp" "$out"
fi
echo "$out"
