#!/usr/bin/env bash
# The fuzz harness (issue 12 item 7; crates/fuzz, a workspace member outside default-members, so
# CI never builds it). Mutated inputs go through the TSP/1 decoder, the CSV dialect, the app's
# file loader, `propid identify` and `propid diagnose`, each under catch_unwind; any panic is
# counted and its input saved in target/fuzz-out/. Seeds: tests/data, and TSP/1 recordings the
# simulated stand writes here (clean, with link faults, with the device clock wrapping at
# 2 kHz), plus any SEED_DIR given (real logs, CSV-stream recordings of `propid run --record`).
#
#   nice -n 10 scripts/fuzz.sh [N [SEED_DIR...]]     (N inputs, default 10000000; FUZZ_SEED=1)
#
# Exit 0 when no input panicked, 1 otherwise. Takes ~15 CPU-minutes for 10^7 inputs.
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-10000000}
shift || true
cargo build --release -p propid -p propid-fuzz >&2
BIN=target/release/propid
SEEDS=$(mktemp -d /tmp/propid-fuzz-seeds.XXXXXX)
trap 'rm -rf "$SEEDS"' EXIT
"$BIN" sim --record "$SEEDS/clean.tsp" --seconds 6 >/dev/null
"$BIN" sim --record "$SEEDS/faults.tsp" --seconds 6 --seed 3 --bit-flips 1e-3 --garbage 5 \
  --drop-samples 0.01 --drop-burst 0.001 >/dev/null
"$BIN" sim --record "$SEEDS/wrap.tsp" --seconds 4 --initial-t-us 4294000000 --rate 2000 >/dev/null
target/release/propid-fuzz --inputs "$N" --seed "${FUZZ_SEED:-1}" --out target/fuzz-out \
  --identify-every 100 --diagnose-every 1000 tests/data "$SEEDS" "$@" >/dev/null
