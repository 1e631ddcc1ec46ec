#!/usr/bin/env bash
# Installs a real C++ YARP 3.5 WITH its device plugins for the live interoperability tests.
#
# Source: PyPI's yarp-middleware 3.5.0 sdist, which holds YARP's whole source tree
# (src/devices included). It is built with CMake directly (not pip: pip's build has no device
# plugins and needs SWIG) into a prefix under ~/.cache/yarp-rs/ whose name carries a stamp
# of this recipe, so a warm run only checks that the prefix exists.
#
# Built: the libraries and programs (yarp, yarpserver, yarpdev, yarprobotinterface, yarprun,
# ...), every carrier whose dependencies are met (shmem, mjpeg, bayer, human, xmlrpc, tcpros,
# portmonitor, unix_stream, websocket; tcp, fast_tcp, text, udp and mcast are built into
# YARP_os), the depthimage_compression_zlib port monitor (ergoCub's depth repeater names it),
# and the device plugins listed in $devices below. Off: GUIs, bindings, tests, examples and
# every other device.
#
# Prints the bin directory (YARP_CPP_BIN) on stdout. With --env it prints shell assignments
# instead: YARP_CPP_BIN and YARP_DATA_DIRS (where `yarpdev` finds the plugin manifests;
# the test-support crate sets the latter for its C++ children by itself).
set -euo pipefail

version=3.5.0
sdist_url=https://files.pythonhosted.org/packages/1d/3d/b5a491c21b122d9cdd65826a1cd5d7ba51580f9f84a6ebfc315beb048d30/yarp_middleware-3.5.0.tar.gz
sdist_sha256=7a8f78e1b6d3477fcd5e73fd5839ebf6971c3c0f5d3208d3ec0ee2b0c44507b9

# The device plugins the tests use (3.5 names; 3.12 renamed some, see the tests).
devices=(
    fakeMotionControl controlBoard_nws_yarp controlboardwrapper2 remote_controlboard
    controlboardremapper remotecontrolboardremapper fakeMotor test_motor
    fakeFrameGrabber test_grabber frameGrabber_nws_yarp frameGrabber_nwc_yarp grabberDual
    remote_grabber
    multipleanalogsensorsserver multipleanalogsensorsclient multipleanalogsensorsremapper
    fakeIMU inertial fakeAnalogSensor analogServer analogsensorclient virtualAnalogServer
    fakeDepthCamera rgbdSensor_nws_yarp
    group pipe
)
cmake_options=(
    -DCMAKE_BUILD_TYPE=Release
    -DBUILD_SHARED_LIBS=ON
    -DYARP_COMPILE_EXECUTABLES=ON
    -DYARP_COMPILE_GUIS=OFF
    -DYARP_COMPILE_BINDINGS=OFF
    -DYARP_COMPILE_TESTS=OFF
    -DYARP_COMPILE_EXAMPLES=OFF
    -DYARP_COMPILE_UNMAINTAINED=OFF
    -DYARP_COMPILE_libYARP_math=ON
    -DYARP_COMPILE_CARRIER_PLUGINS=ON
    -DYARP_COMPILE_DEVICE_PLUGINS=ON
    -DENABLE_yarpcar_human=ON
    -DENABLE_yarpcar_mjpeg=ON
    -DENABLE_yarpcar_websocket=ON
    -DENABLE_yarpcar_shmem=ON
    -DENABLE_yarpcar_portmonitor=ON
    -DYARP_COMPILE_PORTMONITOR_PLUGINS=ON
    -DENABLE_yarppm_depthimage_compression_zlib=ON
)
# The 2021 sources need these on a current toolchain (see ../shared/cpp-yarp-peer.md).
export CMAKE_POLICY_VERSION_MINIMUM=3.5
export CXXFLAGS="-include utility -include cstdint -include limits -include iterator \
 -include algorithm -include memory -include string -include cstring -include mutex \
 -include functional -include stdexcept -include array"
apt_packages=(cmake ninja-build ycm-cmake-modules libace-dev libeigen3-dev libsqlite3-dev
    libjpeg-dev zlib1g-dev g++ curl)

stamp=$(printf '%s\n' "$version" "${devices[*]}" "${cmake_options[*]}" "$CXXFLAGS" \
    "${apt_packages[*]}" | sha256sum | cut -c1-12)
cache=${YARP_CPP_CACHE:-$HOME/.cache/yarp-rs}
prefix=${YARP_CPP_PREFIX:-$cache/cpp-yarp-$version-$stamp}

report() {
    if [[ ${1:-} == --env ]]; then
        printf 'YARP_CPP_BIN=%q\nYARP_DATA_DIRS=%q\n' "$prefix/bin" "$prefix/share/yarp"
    else
        echo "$prefix/bin"
    fi
}
# A finished install leaves its marker last, so an interrupted build is redone. The link
# cpp-yarp -> the current prefix is where the tests look when YARP_CPP_BIN is not set.
if [[ -e $prefix/.installed ]]; then
    ln -sfn "$prefix" "$cache/cpp-yarp"
    report "${1:-}"; exit 0
fi

log() { echo "install-cpp-yarp: $*" >&2; }
missing=()
for p in "${apt_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
    if [[ $(id -u) != 0 ]]; then log "needs the Debian packages: ${missing[*]}"; exit 1; fi
    log "apt-get install ${missing[*]}"
    { apt-get install -y --no-install-recommends "${missing[@]}" ||
        { apt-get update && apt-get install -y --no-install-recommends "${missing[@]}"; }; } >&2
fi

# The sdist pip would fetch (`pip download --no-binary :all: yarp-middleware==3.5.0` also
# builds its build-time dependencies from source first, which takes longer than YARP).
work=$cache/cpp-yarp-build-$stamp
mkdir -p "$work"
tarball=$cache/yarp_middleware-$version.tar.gz
if ! echo "$sdist_sha256  $tarball" | sha256sum -c --status 2>/dev/null; then
    log "downloading $sdist_url"
    curl -fsSL --retry 3 -o "$tarball.part" "$sdist_url"
    echo "$sdist_sha256  $tarball.part" | sha256sum -c --status ||
        { log "checksum mismatch for $sdist_url"; exit 1; }
    mv "$tarball.part" "$tarball"
fi
src=$work/yarp_middleware-$version
[[ -e $src/CMakeLists.txt ]] || tar -C "$work" -xzf "$tarball"

start=$SECONDS
build=$work/build
configure() { cmake -S "$src" -B "$build" -G Ninja -DCMAKE_INSTALL_PREFIX="$prefix" "$@" >&2; }
log "configuring into $build"
configure "${cmake_options[@]}"
# Every device plugin defaults on when its dependencies are met; keep only $devices.
mapfile -t all_devices < <(sed -n 's/^ENABLE_yarpmod_\([^:-]*\):BOOL=.*/\1/p' "$build/CMakeCache.txt")
toggles=()
for d in "${all_devices[@]}"; do
    if [[ " ${devices[*]} " == *" $d "* ]]; then toggles+=("-DENABLE_yarpmod_$d=ON")
    else toggles+=("-DENABLE_yarpmod_$d=OFF"); fi
done
configure "${toggles[@]}"
for d in "${devices[@]}"; do
    grep -q "^ENABLE_yarpmod_$d:BOOL=ON" "$build/CMakeCache.txt" ||
        { log "device plugin $d cannot be enabled (see $build/CMakeCache.txt)"; exit 1; }
done
log "building (-j${YARP_CPP_JOBS:-2}); about 25 minutes on 2 cores"
cmake --build "$build" -j "${YARP_CPP_JOBS:-2}" >&2
cmake --install "$build" >&2
# The plugins must be found where the tests look for them (YARP_DATA_DIRS, as --env says).
listed=$(YARP_DATA_DIRS=$prefix/share/yarp "$prefix/bin/yarpdev" --list 2>&1)
for d in "${devices[@]}"; do
    grep -q "\"$d\"" <<<"$listed" || { log "yarpdev --list lacks $d:"; echo "$listed" >&2; exit 1; }
done
[[ -e $prefix/share/yarp/plugins/depthimage_compression_zlib.ini ]] ||
    { log "the depthimage_compression_zlib port monitor was not built (see $build/CMakeCache.txt)"; exit 1; }
touch "$prefix/.installed"
ln -sfn "$prefix" "$cache/cpp-yarp"
log "built and installed in $((SECONDS - start)) s: $prefix"
rm -rf "$work"
report "${1:-}"
