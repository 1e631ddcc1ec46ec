#!/usr/bin/env bash
# Builds the C++ stack the robots run, from the trimmed sources in ../shared/peers, for the
# live tests: C++ YARP 3.12.3 with icub-main 2.11.1's Ethernet host (`icub`), or C++ YARP
# 4.0.0 alone (`yarp4`: icub-main 2.11.1 does not build against YARP 4).
#
#   tests/peers/install-cpp-peers.sh icub|yarp4 [--env]
#
# The recipe is ../shared/peers/build.sh (see its README); this script adds what the tests
# need on top of it and caches the result:
# - a prefix under ~/.cache/yarp-rs named by a stamp of the sources, the recipe and this
#   script, so a warm run only checks that the prefix is complete (`.installed`, written last);
# - a build directory kept between stamps and compiled through ccache, so a change of recipe
#   recompiles only what changed;
# - icub-main's devices that robots name but build.sh leaves off (rawValuesPublisher server,
#   remapper and client), enabled on the configured build.
#
# Prints the bin directory on stdout; with --env, shell assignments (the bin directory as
# YARP_CPP312_BIN or YARP_CPP4_BIN, and the YARP_DATA_DIRS its programs need). The link
# ~/.cache/yarp-rs/cpp-icub (or cpp-yarp4) points at the current prefix.
set -euo pipefail

which=${1:?usage: $0 icub|yarp4 [--env]}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
peers=${CPP_PEERS_SRC:-$(cd "$here/../../.." && pwd)/shared/peers}
[[ -x $peers/build.sh || -f $peers/build.sh ]] ||
    { echo "install-cpp-peers: no $peers/build.sh (expected ../shared/peers beside the repository)" >&2; exit 1; }

apt_packages=(cmake g++ make ninja-build pkg-config libace-dev libsqlite3-dev libeigen3-dev
    libjpeg-dev zlib1g-dev libtinyxml-dev libedit-dev ccache libi2c-dev)
# Devices of YARP kept on top of build.sh's list: the fakes our live tests serve from C++,
# deviceBundler, through which a real yarpdev serves a device that has a wrapper, and devices
# robots' files name: the head IMU of several iCubs (imuBosch_BNO055: YARP builds it only
# with libi2c's headers) and R1's odometry wrapper with its client and fake.
extra_yarp_3="fakeAnalogSensor deviceBundler imuBosch_BNO055 odometry2D_nws_yarp odometry2D_nwc_yarp fakeOdometry2D"
extra_yarp_4=""
# icub-main devices robots' files name that build.sh leaves off. (fineCalibrationChecker is
# not among them: it draws its report with OpenCV, which build.sh turns off, and no robot of
# robots-configuration names it.)
extra_icub=(rawValuesPublisherServer rawValuesPublisherRemapper rawValuesPublisherClient)

case $which in
    icub) name=cpp-icub; yarp_src=yarp-3.12.3; env_file=icubhost-env.sh; bin_var=YARP_CPP312_BIN ;;
    yarp4) name=cpp-yarp4; yarp_src=yarp-4.0.0; env_file=yarp-env.sh; bin_var=YARP_CPP4_BIN ;;
    *) echo "install-cpp-peers: unknown peer '$which' (icub or yarp4)" >&2; exit 2 ;;
esac

# The stamp: the contents of the sources this peer builds from, the recipe, this script.
trees=(ycm "$yarp_src")
[[ $which == icub ]] && trees+=(icub-firmware-shared icub-main)
stamp=$( {
    (cd "$peers/src" && find "${trees[@]}" -type f -print0 | sort -z | xargs -0 sha256sum)
    cat "$peers/build.sh" "${BASH_SOURCE[0]}"   # contents only: CI's copy lives elsewhere
    printf '%s\n' "${apt_packages[*]}"
} | sha256sum | cut -c1-12)
cache=${YARP_CPP_CACHE:-$HOME/.cache/yarp-rs}
prefix=$cache/$name-$stamp
build_dir=$cache/$name-build

report() {
    local data
    if [[ $which == icub ]]; then data=$prefix/share/yarp:$prefix/share/iCub; else data=$prefix/share/yarp; fi
    if [[ ${1:-} == --env ]]; then
        printf '%s=%q\nYARP_DATA_DIRS=%q\n' "$bin_var" "$prefix/bin" "$data"
    else
        echo "$prefix/bin"
    fi
}
if [[ -e $prefix/.installed ]]; then
    ln -sfn "$prefix" "$cache/$name"
    report "${2:-}"; exit 0
fi

log() { echo "install-cpp-peers($which): $*" >&2; }
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

start=$SECONDS
# CMake ties a build directory to its sources' path: one made from sources elsewhere (a CI
# run's copy of ../shared) cannot be reused, so it is started anew (ccache still helps).
if [[ -f $build_dir/ycm/CMakeCache.txt ]] &&
    ! grep -qx "CMAKE_HOME_DIRECTORY:INTERNAL=$peers/src/ycm" "$build_dir/ycm/CMakeCache.txt"; then
    log "the build directory was made from sources elsewhere: starting it anew"
    rm -rf "$build_dir"
fi
export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache
export CCACHE_DIR=${CCACHE_DIR:-$cache/ccache} CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-3G}
export JOBS=${CPP_PEERS_JOBS:-2}
mkdir -p "$prefix" "$build_dir"
# build.sh keeps the devices of its list (forced ON): ours are added to it.
if [[ $which == icub ]]; then
    keep=$(sed -n '/^YARP_KEEP_3="/,/"$/p' "$peers/build.sh" | tr -d '"' | sed 's/^YARP_KEEP_3=//')
    export YARP_KEEP="$keep $extra_yarp_3"
    log "building YARP 3.12.3 and icub-main 2.11.1 into $prefix (cold: about 20 minutes on 2 cores)"
    # The kept build directory remembers the options this script set last time; build.sh
    # configures icub-main with its own, so ours are reset first and set again after it.
    cache_file=$build_dir/icub-main/CMakeCache.txt
    [[ ! -f $cache_file ]] || sed -i 's/^\(ENABLE_icubmod_\(rawValuesPublisher[A-Za-z]*\|fineCalibrationChecker\):BOOL=\)ON$/\1OFF/' "$cache_file"
    # A kept YARP device that an earlier configure turned off (YARP_SLIM, or a dependency
    # then missing, as libi2c for imuBosch_BNO055) is turned on again before build.sh runs.
    yarp_cache=$build_dir/$yarp_src/CMakeCache.txt
    for d in $extra_yarp_3; do
        [[ ! -f $yarp_cache ]] || sed -i "s/^ENABLE_yarpmod_$d:BOOL=OFF$/ENABLE_yarpmod_$d:BOOL=ON/" "$yarp_cache"
    done
    bash "$peers/build.sh" "$prefix" "$build_dir" >&2
    # The icub-main devices build.sh leaves off, on the configured build.
    opts=()
    for d in "${extra_icub[@]}"; do opts+=("-DENABLE_icubmod_$d=ON"); done
    opts+=(-DENABLE_icubmod_fineCalibrationChecker=OFF)
    cmake -S "$peers/src/icub-main" -B "$build_dir/icub-main" "${opts[@]}" >&2
    cmake --build "$build_dir/icub-main" --parallel "$JOBS" >&2
    cmake --install "$build_dir/icub-main" >&2
else
    keep=$(sed -n '/^YARP_KEEP_4="/,/"$/p' "$peers/build.sh" | tr -d '"' | sed 's/^YARP_KEEP_4=//')
    export YARP_KEEP="$keep $extra_yarp_4"
    log "building YARP 4.0.0 into $prefix (cold: about 20 minutes on 2 cores)"
    YARP_SRC=yarp-4.0.0 YARP_ONLY=1 bash "$peers/build.sh" "$prefix" "$build_dir" >&2
fi

# Check what the tests rely on before calling the prefix complete.
# shellcheck disable=SC1090
listed=$( . "$prefix/$env_file"; export YARP_CONFIG_HOME=$(mktemp -d); yarpdev --list 2>&1; rm -rf "$YARP_CONFIG_HOME")
want=(controlBoard_nws_yarp multipleanalogsensorsserver fakeMotionControl)
[[ $which == icub ]] && want+=(embObjMotionControl embObjFTsensor embObjMultipleFTsensors embObjIMU
    embObjMais embObjSkin embObjPOS embObjBattery parametricCalibratorEth "${extra_icub[@]}"
    imuBosch_BNO055 odometry2D_nws_yarp odometry2D_nwc_yarp)
for d in "${want[@]}"; do
    grep -q "\"$d\"" <<<"$listed" || { log "yarpdev --list lacks $d:"; echo "$listed" >&2; exit 1; }
done
touch "$prefix/.installed"
ln -sfn "$prefix" "$cache/$name"
# Older prefixes of this peer are stale once a new one is complete.
for old in "$cache/$name"-*; do
    [[ $old == "$prefix" || $old == "$build_dir" || ! -d $old ]] || rm -rf "$old"
done
log "built and installed in $((SECONDS - start)) s: $prefix"
report "${2:-}"
