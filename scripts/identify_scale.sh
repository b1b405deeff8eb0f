#!/usr/bin/env bash
# Whole-process time and peak memory of `propid identify --hankel square --order 2` on one-pulse
# records of 1 000, 4 000 and 100 000 samples (issue 6 item 2: 100 000 samples, Hankel
# ≈ 50 000 × 50 000 blocks, under 1 s and under 64 MB peak). Release build, one process per
# size; wall time measured around the process (includes reading the CSV), peak memory as
# "Maximum resident set size" from /usr/bin/time -v. Not run by CI.
#
# Record: exact discrete 2nd-order plant (fn 20 Hz, ζ 0.3, 1 kHz), one one-sample throttle pulse
# (1300 → 1500 µs) at sample 100, thrust noise-free; CSV `t_s,throttle_us,thrust_N`.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet --bin propid
bin=target/release/propid
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for n in ${SIZES:-1000 4000 100000}; do
    f="$tmp/pulse_$n.csv"
    awk -v n="$n" 'BEGIN {
        pi = atan2(0, -1); dt = 0.001; w = 2 * pi * 20; z = 0.3;
        r = exp(-z * w * dt); th = w * sqrt(1 - z * z) * dt;
        a1 = 2 * r * cos(th); a2 = -r * r; b = (1 - a1 - a2) / 2;
        print "t_s,throttle_us,thrust_N";
        for (k = 0; k < n; k++) { u[k] = (k == 100) ? 1500 : 1300; un[k] = (u[k] - 1000) / 1000 }
        y[0] = un[0]; y[1] = un[0];
        for (k = 2; k < n; k++) y[k] = a1 * y[k-1] + a2 * y[k-2] + b * (un[k-1] + un[k-2]);
        for (k = 0; k < n; k++) printf "%.6f,%.3f,%.12f\n", k * dt, u[k], y[k];
    }' > "$f"
    t0=$(date +%s%N)
    /usr/bin/time -v "$bin" identify "$f" --hankel square --order 2 --json \
        > "$tmp/out.json" 2> "$tmp/time.txt"
    t1=$(date +%s%N)
    wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.0f ms", (b - a) / 1e6}')
    rss=$(awk -F': ' '/Maximum resident set size/ {printf "%.1f MiB", $2 / 1024}' "$tmp/time.txt")
    model=$(tr -d ' \n' < "$tmp/out.json" |
        grep -o '"hankel_block_rows":[0-9]*,"hankel_block_cols":[0-9]*' |
        sed 's/"hankel_block_rows"://; s/,"hankel_block_cols":/ x /')
    fz=$(tr -d ' \n' < "$tmp/out.json" | grep -o '"fn_hz":[^,]*,"zeta":[^,]*' | head -1)
    echo "samples $n | Hankel $model blocks | wall $wall | peak RSS $rss | $fz"
done
