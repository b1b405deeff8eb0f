#!/usr/bin/env bash
# Runs a propid binary over the output corpus and writes every JSON output (and exit code) into
# one file per run, so that two builds can be compared with `diff -r`:
#
#   scripts/corpus_outputs.sh BIN OUTDIR [RECDIR]
#
# The corpus: every CSV/TXT file under tests/data and ../shared/data (identify --json and
# diagnose --json, the headerless noahcurtiss logs also with --columns), and simulated-stand
# recordings (TSP/1 and CSV wire, with and without faults) made by BIN into RECDIR (default
# OUTDIR/rec; pass an existing RECDIR to reuse the same recordings for a second binary), each
# identified, diagnosed and replayed (replay lines minus wall-clock latency fields).
#
# Used for issue 10 (the workspace split must not change an output unless a unified rule says
# so): run it with the old and the new binary and diff the two folders.
set -uo pipefail
cd "$(dirname "$0")/.."
bin="$(realpath "$1")"
out="$2"
rec="${3:-$out/rec}"
data="${PROPID_SHARED_DATA:-../shared/data}"
mkdir -p "$out" "$rec"

run() { # name, then the command's arguments
    local name="$1"
    shift
    "$bin" "$@" >"$out/$name.out" 2>"$out/$name.err"
    echo "exit $?" >>"$out/$name.out"
}

# Files: tests/data and ../shared/data.
files=$(find tests/data -type f \( -name '*.csv' -o -name '*.txt' \) | sort)
if [ -d "$data" ]; then
    files="$files $(find "$data" -type f \( -name '*.csv' -o -name '*.txt' \) ! -name 'README*' | sort)"
fi
for f in $files; do
    name=$(echo "$f" | sed 's#^\.\./shared/data/##; s#^tests/data/#t-#; s#/#__#g')
    run "$name.identify" identify --json "$f"
    run "$name.diagnose" diagnose --json "$f"
done
if [ -d "$data/noahcurtiss-blctrl-steps" ]; then
    for f in "$data"/noahcurtiss-blctrl-steps/*.txt; do
        name=$(basename "$f")
        run "$name.cols.identify" identify --json --columns cmd,force --fs 50 "$f"
        run "$name.cols.diagnose" diagnose --json --columns cmd,force --fs 50 "$f"
    done
fi

# Simulated-stand recordings (made once; reused when RECDIR already holds them).
make_rec() { # name, then sim override flags
    local name="$1"
    shift
    [ -s "$rec/$name" ] || "$bin" sim --record "$rec/$name" --seconds 12 "$@" >/dev/null 2>&1
}
make_rec clean.tsp --seed 1
make_rec faults.tsp --seed 2 --bit-flips 0.0005 --garbage 0.5 --drop-samples 0.002
# A CSV-wire stand cannot be recorded faster than real time: the daemon records it live over
# the pty (so these two differ from run to run; reuse RECDIR to compare two binaries).
live_csv_rec() { # name, then sim override flags
    local name="$1" link="$rec/.link-$1" cfg="$rec/.daemon.toml"
    shift
    [ -s "$rec/$name" ] && return
    printf '[daemon]\nmax_run_s = 11\n[experiment]\nlevels = [0.3, 0.5]\npulses_per_level = 8\n' >"$cfg"
    "$bin" sim --protocol csv --link "$link" --seconds 14 "$@" >/dev/null 2>&1 &
    local sim=$!
    sleep 0.5
    "$bin" run --config "$cfg" --port "$link" --record "$rec/$name" >/dev/null 2>&1
    kill "$sim" 2>/dev/null
    wait "$sim" 2>/dev/null
}
live_csv_rec clean.csv --seed 3
live_csv_rec faults.csv --seed 4 --bit-flips 0.0005 --drop-samples 0.002
make_rec rate2k.tsp --seed 5 --rate 2000
# Wall-clock fields of the daemon's lines differ from run to run: dropped before comparing.
strip_clock='
import json, sys
for line in sys.stdin:
    try:
        v = json.loads(line)
    except ValueError:
        print(line, end="")
        continue
    if isinstance(v, dict):
        for k in [k for k in v if k.startswith(("latency", "elapsed", "wall"))]:
            del v[k]
    print(json.dumps(v, sort_keys=True))
'
for r in "$rec"/*; do
    name="sim-$(basename "$r")"
    run "$name.identify" identify --json "$r"
    run "$name.diagnose" diagnose --json "$r"
    "$bin" replay "$r" 2>"$out/$name.replay.err" | python3 -c "$strip_clock" >"$out/$name.replay.out"
done
echo "corpus: $(ls "$out" | wc -l) files in $out"
