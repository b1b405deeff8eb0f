#!/usr/bin/env bash
# The reference firmware in the loop: builds firmware/ (the ELF a user flashes) and its simavr
# harness, runs the ELF on an emulated ATmega328P whose UART is a pty and whose ESC, HX711 and
# rpm pins are wired to the simulated motor (`propid sim --plant-pipe`), and runs `propid run`
# against it. stdout: the daemon's JSON lines; the harness's log goes to stderr at the end.
#   scripts/firmware_loopback.sh [--kind K] [--seconds S]
# --kind: the experiment plan's kind: pulses (the default), staircase, ramp or chirp, each with
# keys that finish within 25 s. --seconds: the run's limit (daemon max_run_s, default 25).
set -euo pipefail
cd "$(dirname "$0")/.."
kind=pulses
seconds=25
while [ $# -gt 0 ]; do
    case "$1" in
        --kind) kind="$2"; shift 2 ;;
        --seconds) seconds="$2"; shift 2 ;;
        *) echo "usage: $0 [--kind K] [--seconds S]" >&2; exit 2 ;;
    esac
done
scripts/install_avr_tools.sh >&2
make -s -C firmware >&2
cargo build --release --quiet >&2
bin="$PWD/target/release/propid"
dir="$(mktemp -d)"
harness_pid=""
cleanup() {
    if [ -n "$harness_pid" ]; then kill "$harness_pid" 2>/dev/null || true; wait "$harness_pid" 2>/dev/null || true; fi
    if [ -s "$dir/harness.log" ]; then echo "--- harness" >&2; cat "$dir/harness.log" >&2; fi
    rm -rf "$dir"
}
trap cleanup EXIT
# each kind's keys, sized to finish within the default 25 s (docs/experiment-kinds.md)
case "$kind" in
    pulses) kind_keys='levels = [0.3, 0.45, 0.6]' ;;
    staircase) kind_keys=$'kind = "staircase"\nlevels = [0.3, 0.45, 0.6]\nhold_ms = 2000' ;;
    ramp) kind_keys=$'kind = "ramp"\nlevels = [0.3, 0.6]\nramp_rate_per_s = 0.05\nhold_ms = 1000' ;;
    chirp) kind_keys=$'kind = "chirp"\nlevels = [0.45]\nchirp_f0_hz = 1.0\nchirp_f1_hz = 15.0\nchirp_amplitude = 0.05\nchirp_s = 12.0' ;;
    *) echo "firmware_loopback: --kind is one of pulses, staircase, ramp, chirp" >&2; exit 2 ;;
esac
cat >"$dir/propid.toml" <<TOML
[device]
baud = 250000
reconnect_initial_ms = 50
reconnect_max_ms = 500
[daemon]
max_run_s = $seconds
[identify]
pulses_per_model = 4
[experiment]
$kind_keys
ramp_ms = 300
settle_ms = 500
pulse_amplitudes = [0.1, 0.15]
pulse_width_samples = 2
pulse_spacing_ms = 250
pulses_per_level = 8
TOML
firmware/build/harness firmware/build/propid-fw.elf --link "$dir/stand" \
    --seconds "$(awk "BEGIN{print $seconds + 10}")" \
    --plant "'$bin' sim --plant-pipe --config config/sim.toml" >"$dir/harness.log" 2>&1 &
harness_pid=$!
for _ in $(seq 100); do [ -e "$dir/stand" ] && break; sleep 0.1; done
[ -e "$dir/stand" ] || { echo "firmware_loopback: the harness made no pty" >&2; exit 1; }
"$bin" run --config "$dir/propid.toml" --port "$dir/stand"
