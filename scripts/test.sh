#!/usr/bin/env bash
# The whole test suite, on a fresh machine too: README's test command, and what .ci/run runs.
# The web page's tests drive headless Chromium (Debian's `chromium`); it is installed here when
# it is missing (apt-get, as root or through sudo), as are the AVR tools of firmware/, then every
# crate's tests run in release.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v chromium >/dev/null; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y chromium
fi
# The reference firmware's tests (tests/firmware) build it with avr-gcc and run it on simavr.
scripts/install_avr_tools.sh
cargo test --release
