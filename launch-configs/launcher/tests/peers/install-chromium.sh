#!/usr/bin/env bash
# Installs Debian's headless-capable Chromium (and its WebDriver) for the dashboard test.
# Idempotent: does nothing when `chromium` is already on PATH. Needs root (apt-get).
# Exit status 0 when chromium is usable afterwards, 1 otherwise (the test then skips loudly).
set -u
if command -v chromium >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "install-chromium: need root and apt-get to install chromium" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq >/dev/null 2>&1 || true
apt-get install -y -qq --no-install-recommends chromium chromium-driver fonts-dejavu-core >/dev/null 2>&1 || {
    echo "install-chromium: apt-get install chromium chromium-driver failed" >&2
    exit 1
}
command -v chromium >/dev/null 2>&1
