#!/usr/bin/env bash
# The whole test suite, on a fresh machine too: README's test command, and what .ci/run runs.
# The web page's tests drive headless Chromium (Debian's `chromium`), the MQTT tests a real
# broker and its clients (Debian's `mosquitto`, `mosquitto-clients`); they are installed here
# when missing (apt-get, as root or through sudo), as are the AVR tools of firmware/, then every
# crate's tests run in release.
set -euo pipefail
cd "$(dirname "$0")/.."
MISSING=()
command -v chromium >/dev/null || MISSING+=(chromium)
{ command -v mosquitto >/dev/null || [ -x /usr/sbin/mosquitto ]; } || MISSING+=(mosquitto)
command -v mosquitto_sub >/dev/null || MISSING+=(mosquitto-clients)
if [ ${#MISSING[@]} -gt 0 ]; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y "${MISSING[@]}"
fi
# The reference firmware's tests (tests/firmware) build it with avr-gcc and run it on simavr.
scripts/install_avr_tools.sh
cargo test --release
