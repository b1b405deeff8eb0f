#!/usr/bin/env bash
# Daemon benchmarks (not run by CI; timing targets live here, never in tests):
#  1. replay speed: one hour of a 1 kHz recording through `propid replay` (target < 2 s);
#  2. live throughput: the simulated stand at RATE samples/s on a pty, `propid run` against it for
#     SECONDS s: samples/s sustained, samples lost, queue overflows, frames dropped
#     (target: 10 kHz on 2 cores without loss);
#  3. latency from the last sample of an identification window to its published model line,
#     p50 and p99, from the live run's stats line.
# Usage: scripts/bench_daemon.sh [RATE=10000] [SECONDS=10]
#
# Measured 2026-11-21 on the 2-core project machine under load average ~16 (other builds running;
# wall times there are 3-4x the CPU times, so CPU times are quoted):
#  - live, sim at 10 kHz: 100 035 samples in 10.0 s, 0 lost, 0 overflows, 0 frames dropped;
#    daemon CPU 0.46 s user + 0.18 s sys (~6 % of a core). At 20 kHz: 200 121 samples, 0 lost
#    (00:18 UTC: 200 019, 0 lost; with 1 ms pulses 6 models + 17 model_unreliable).
#  - latency last sample -> model line (10 kHz, K = 4): p50 27 ms, p99 138 ms (loaded machine;
#    dominated by the identification itself); 2026-11-21 23:49 UTC after the issue-3 perf work,
#    load ~2: p50 2.2 ms, p99 2.7 ms. 2026-11-22 00:16 UTC, load ~1.4, with 1 ms pulses
#    (pulse_width_samples = 10; with one-sample pulses at 10 kHz nearly every window is below
#    the noise and fails or is withheld as model_unreliable): 23 models, p50 1.18 ms, p99 1.78 ms.
#  - replay of one hour at 1 kHz (3.6 M samples, 145 MB, 3 582 windows with the jackknife;
#    since the quality checks 3 573 models + 9 model_unreliable; 2026-11-22 00:16 UTC, load
#    ~1.4: 1.76 s and 1.92 s wall in two runs),
#    measured 2026-11-21 23:49 UTC (load average ~2 from other jobs): 1.90 s wall, 2.87 s user
#    + 0.15 s sys CPU (target < 2 s: met when two cores are free; 2.9 s when another job holds
#    one). Per thread (perf): worker ~1.75 s (identification; the model's small Jacobi SVD is
#    half of it), jackknife helper ~0.7 s, sampler (decoding) ~0.6 s, main ~0.1 s. Before the
#    issue-3 perf work: 10.0-10.4 s wall, 10.8 s CPU (the Lanczos bidiagonal's Jacobi SVD at
#    every convergence check and in every jackknife re-identification).
set -euo pipefail
cd "$(dirname "$0")/.."
rate="${1:-10000}"
seconds="${2:-10}"
cargo build --release --quiet
bin="$PWD/target/release/propid"
work="$(mktemp -d)"
trap 'kill ${sim_pid:-} 2>/dev/null || true; rm -rf "$work"' EXIT

# --- 1. replay speed ------------------------------------------------------------------------
# A 1 kHz stand running pulses at three operating points for an hour (4800 pulses per level).
cat > "$work/sim_hour.toml" <<TOML
[stand]
sample_rate_hz = 1000
[experiment]
levels = [0.3, 0.45, 0.6]
pulses_per_level = 4800
TOML
"$bin" sim --config "$work/sim_hour.toml" --record "$work/hour.tsp" --seconds 3600 2>/dev/null
bytes=$(stat -c %s "$work/hour.tsp")
/usr/bin/time -f '%e %U %S' -o "$work/replay.time" "$bin" replay "$work/hour.tsp" > "$work/replay.jsonl"
read -r replay_s user_s sys_s < "$work/replay.time"
stats=$(tail -n 1 "$work/replay.jsonl")
samples=$(echo "$stats" | python3 -c 'import json,sys; print(json.load(sys.stdin)["samples"])')
models=$(echo "$stats" | python3 -c 'import json,sys; print(json.load(sys.stdin)["models"])')
unreliable=$(echo "$stats" | python3 -c 'import json,sys; print(json.load(sys.stdin)["models_unreliable"])')
printf 'replay: %d samples (%.1f min of 1 kHz), %d bytes, %d models (+%d model_unreliable) in %.3f s wall (%.2f s user + %.2f s sys CPU, 3 threads) = %.2f M samples/s\n' \
    "$samples" "$(echo "$samples / 60000" | bc -l)" "$bytes" "$models" "$unreliable" "$replay_s" "$user_s" "$sys_s" \
    "$(echo "$samples / $replay_s / 1000000" | bc -l)"
printf 'load average (1, 5, 15 min) just after: %s\n' "$(cut -d' ' -f1-3 /proc/loadavg)"

# --- 2 + 3. live throughput and latency ---------------------------------------------------------
cat > "$work/sim_fast.toml" <<TOML
[stand]
sample_rate_hz = $rate
TOML
cat > "$work/run.toml" <<TOML
[daemon]
max_run_s = $seconds
[identify]
max_window_samples = 262144
[experiment]
levels = [0.3, 0.45, 0.6]
ramp_ms = 200
settle_ms = 300
pulse_amplitudes = [0.1, 0.15]
pulse_spacing_ms = 100
pulses_per_level = 1000
# 1 ms pulses: one-sample pulses at 10 kHz are below the noise (model_unreliable, see docs/daemon.md)
pulse_width_samples = $(( rate >= 2000 ? rate / 1000 : 1 ))
TOML
"$bin" sim --config "$work/sim_fast.toml" --link "$work/stand" --seconds $((seconds + 5)) \
    > /dev/null 2>&1 &
sim_pid=$!
for _ in $(seq 100); do [ -e "$work/stand" ] && break; sleep 0.05; done
"$bin" run --config "$work/run.toml" --port "$work/stand" > "$work/live.jsonl"
tail -n 1 "$work/live.jsonl" | python3 -c '
import json, sys
s = json.load(sys.stdin)
drop = sum(s["frames_dropped"].values())
lat = s.get("latency_s") or {}
fmt = lambda x: "n/a" if x is None else "%.2f ms" % (1e3 * x)
print("live: %d samples in %.2f s = %.0f samples/s; lost %d, overflows %d, frames dropped %d; "
      "models %d (+%d model_unreliable, %d failed)"
      % (s["samples"], s["elapsed_s"], s["samples"] / s["elapsed_s"], s["samples_lost"],
         s["overflows"], drop, s["models"], s["models_unreliable"], s["identify_errors"]))
print("latency last sample -> model line: p50 %s, p99 %s" % (fmt(lat.get("p50")), fmt(lat.get("p99"))))
'
