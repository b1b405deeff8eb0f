#!/usr/bin/env bash
# Times `propid diagnose` as a whole process on issue 31's cases, two builds paired in one run
# (A B A B ..., RUNS times each): CPU time (user + sys) and wall time from /usr/bin/time; per
# case the median of each and the median of the pairwise CPU ratios A/B. CPU time is the figure
# to read on a shared machine (wall time there follows the load, not the build). With one
# binary, its times alone. With CHECK=1 also whether both builds print the same `--json`
# (byte for byte). Not run by CI; the numbers are in docs/speed.md.
#
#   scripts/diagnose_time.sh BIN [OTHER_BIN] [RUNS]          (RUNS default 3)
#
# Cases (made here, nothing committed; CASES="..." picks some):
# - tyto: a 16 000-row Tyto/RCbenchmark-style step test at 143 Hz (ESC 1000 → 1950 µs in
#   50 µs steps, then down in 200 µs steps; a rotor of 40 ms behind 30 ms; thrust through a
#   load cell of 0.10 s delay and 0.15 s lag, refreshed at 7 Hz and held between; voltage,
#   current, rpm);
# - silverbox: Silverbox's estimation record, the 65 000 samples of SNLS80mV.csv from row
#   40 700 (its multisines; ../shared/data, or PROPID_SHARED_DATA);
# - stair20k, stair40k, stair60k, stair80k: 1 kHz staircases (random levels 0.2..0.8 held 3 s,
#   thrust 900 gf · u² through a 40 ms lag and a 10 ms dead time, deterministic noise);
# - cf21: the bitcraze cf21 log (../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
bin="$(realpath "$1")"
other="${2:-}"
[ -z "$other" ] || other="$(realpath "$other")"
runs="${3:-3}"
data="${PROPID_SHARED_DATA:-../shared/data}"
cases="${CASES:-tyto silverbox stair20k stair40k stair60k stair80k cf21}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT

staircase() { # samples, file
    awk -v n="$1" 'BEGIN {
        srand(7); dt = 0.001; a = exp(-dt / 0.04); y = 0; d = 10; lv = 0.5
        print "time_s,throttle_pct,thrust_g"
        for (k = 0; k < n; k++) {
            if (k % 3000 == 0) lv = 0.2 + 0.1 * int(7 * rand())
            u[k] = lv
            ud = (k >= d) ? u[k - d] : u[0]
            y = a * y + (1 - a) * 900 * ud * ud
            printf "%.4f,%.2f,%.2f\n", k * dt, 100 * lv, y + 2 * (rand() + rand() + rand() - 1.5)
        }
    }' >"$2"
}

tyto() { # rows, file
    awk -v n="$1" 'BEGIN {
        srand(11); dt = 1 / 143; per = int(n / 24)
        for (i = 0; i < 20; i++) lv[i] = 1000 + 50 * i
        for (i = 0; i < 4; i++) lv[20 + i] = 1750 - 200 * i
        ar = exp(-dt / 0.04); ac = exp(-dt / 0.15); nd = int(0.03 / dt + 0.5); cd = int(0.10 / dt + 0.5)
        w = 0; f = 0; held = 0; hold_next = 0
        print "Time (s),ESC signal (µs),Thrust (gf),Voltage (V),Current (A),Motor Electrical Speed (RPM)"
        for (k = 0; k < n; k++) {
            j = int(k / per); if (j > 23) j = 23
            us[k] = lv[j]
            ud = (k >= nd) ? us[k - nd] : us[0]
            u = (ud - 1000) / 1000; if (u < 0.05) u = 0
            w = ar * w + (1 - ar) * 24000 * sqrt(u)
            t[k] = 1.2e-6 * w * w
            td = (k >= cd) ? t[k - cd] : t[0]
            f = ac * f + (1 - ac) * td
            if (k * dt >= hold_next) { held = f + 2 * (rand() + rand() + rand() - 1.5); hold_next += 1 / 7 }
            i_a = 0.3 + 2.5e-9 * w * w * w / 1000
            printf "%.5f,%d,%.2f,%.3f,%.3f,%.0f\n", k * dt, us[k], held, 16.8 - 0.02 * i_a,
                i_a + 0.02 * (rand() - 0.5), w + 20 * (rand() - 0.5)
        }
    }' >"$2"
}

median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

# One run: "cpu_s wall_s" on stdout; the JSON into $dir/out.json.
timed() { # binary, args...
    local b="$1"
    shift
    /usr/bin/time -f "%U %S %e" -o "$dir/time.txt" "$b" diagnose "$@" --json >"$dir/out.json" 2>"$dir/err.txt" ||
        { echo "failed: $b diagnose $*: $(tail -1 "$dir/err.txt")" >&2 && exit 1; }
    awk '{printf "%.2f %.2f\n", $1 + $2, $3}' "$dir/time.txt"
}

echo "# $runs paired runs each, medians; A $bin${other:+, B $other}; load $(cut -d' ' -f1-3 /proc/loadavg)"
for c in $cases; do
    case "$c" in
    tyto) tyto 16000 "$dir/tyto.csv" && args=("$dir/tyto.csv") ;;
    silverbox)
        [ -f "$data/silverbox/SNLS80mV.csv" ] || continue
        # awk reads the whole file: `tail | head` ends with SIGPIPE, which pipefail and -e
        # turned into a silent exit.
        { echo "V1,V2"; awk 'NR >= 40702 && NR < 40702 + 65000' "$data/silverbox/SNLS80mV.csv" | cut -d, -f1,2; } >"$dir/sb.csv"
        args=("$dir/sb.csv" --input V1 --output V2 --fs 610.35) ;;
    stair*k) n="${c#stair}" && staircase "${n%k}000" "$dir/$c.csv" && args=("$dir/$c.csv") ;;
    cf21)
        [ -f "$data/bitcraze-cf21-pwm-steps/cf21_stock2.csv" ] || continue
        args=(--fs 100 "$data/bitcraze-cf21-pwm-steps/cf21_stock2.csv") ;;
    *) echo "unknown case $c" >&2 && exit 2 ;;
    esac
    : >"$dir/a" && : >"$dir/b" && : >"$dir/r"
    same=""
    for _ in $(seq "$runs"); do
        timed "$bin" "${args[@]}" >>"$dir/a"
        if [ -n "$other" ]; then
            cp "$dir/out.json" "$dir/a.json"
            timed "$other" "${args[@]}" >>"$dir/b"
            paste -d' ' <(tail -1 "$dir/a") <(tail -1 "$dir/b") | awk '{print ($3 > 0) ? $1 / $3 : 0}' >>"$dir/r"
            if [ "${CHECK:-0}" = 1 ]; then
                cmp -s "$dir/a.json" "$dir/out.json" && same="${same:-same JSON}" || same="JSON differs"
            fi
        fi
    done
    a_cpu=$(cut -d' ' -f1 "$dir/a" | median) a_wall=$(cut -d' ' -f2 "$dir/a" | median)
    if [ -n "$other" ]; then
        printf '%-10s A %7.2f s CPU %7.2f s wall | B %7.2f s CPU %7.2f s wall | A/B CPU %.2f %s\n' "$c" \
            "$a_cpu" "$a_wall" "$(cut -d' ' -f1 "$dir/b" | median)" "$(cut -d' ' -f2 "$dir/b" | median)" \
            "$(median <"$dir/r")" "$same"
    else
        printf '%-10s %7.2f s CPU %7.2f s wall\n' "$c" "$a_cpu" "$a_wall"
    fi
done
