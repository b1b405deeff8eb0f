#!/usr/bin/env bash
# Installs what the reference firmware and its emulator harness need (firmware/README.md), when
# missing: Debian's gcc-avr, avr-libc, simavr, libsimavr-dev and libelf-dev (apt-get, as root or
# through sudo). Called by scripts/test.sh and scripts/firmware_loopback.sh.
set -euo pipefail
missing=()
command -v avr-gcc >/dev/null || missing+=(gcc-avr)
[ -e /usr/lib/avr/include/avr/io.h ] || missing+=(avr-libc)
command -v simavr >/dev/null || missing+=(simavr)
[ -e /usr/include/simavr/sim_avr.h ] || missing+=(libsimavr-dev)
[ -e /usr/include/libelf.h ] || [ -e /usr/include/libelf/libelf.h ] || missing+=(libelf-dev)
if [ ${#missing[@]} -gt 0 ]; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y "${missing[@]}"
fi
