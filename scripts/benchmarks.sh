#!/usr/bin/env bash
# Runs the official protocols of three nonlinear-system-identification benchmarks (Silverbox:
# three test sets; Cascaded Tanks; EMPS) on the data in ../shared/data (relative to the project
# root; override with PROPID_SHARED_DATA) the way a user would: the estimation record cut into
# one file, each test record into another; `propid identify --save` (linear) and
# `propid diagnose --save` (extended) on the estimation file only, then `propid compare` on the
# test file with the protocol's initialisation window. Writes the table into docs/benchmarks.md
# between <!-- BEGIN benchmarks --> and <!-- END benchmarks --> (scripts/splice_docs.py).
#
#   scripts/benchmarks.sh            # into docs/benchmarks.md, between the markers
#   scripts/benchmarks.sh OUT.md     # the table to OUT.md instead
#   PROPID_BIN=path/to/propid scripts/benchmarks.sh OUT.md   # score another build
#
# Splits (nonlinear_benchmarks, Champneys et al. 2024): Silverbox SNLS80mV rows 40650..127400
# are the multisines, their first 75 % estimation and the rest the multisine test; rows
# 100..40575 the arrow (full), its first 32000 the arrow without extrapolation; n = 50.
# Cascaded Tanks: uEst/yEst estimation, uVal/yVal test, n = 5. EMPS: DATA_EMPS estimation,
# DATA_EMPS_PULSES test, input vir (N), output qm (m), n = 20.
set -euo pipefail
cd "$(dirname "$0")/.."
data="${PROPID_SHARED_DATA:-../shared/data}"
out="${1:-}"
# PROPID_BIN: another build to score (e.g. main's, for a before/after table).
bin="${PROPID_BIN:-target/release/propid}"
if [ -z "${PROPID_BIN:-}" ]; then
    cargo build --release --quiet --bin propid
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# rms MODEL DATA N SCALE READ-FLAGS...: the test RMS of MODEL on DATA, times SCALE ("–" when
# the model or the comparison is missing).
rms() {
    local model="$1" file="$2" n="$3" scale="$4"
    shift 4
    if [ ! -s "$model" ]; then
        echo "–"
        return
    fi
    local j
    j="$("$bin" compare "$model" "$file" --init-samples "$n" --json "$@" 2>/dev/null)" || {
        echo "–"
        return
    }
    python3 -c "import json,sys; v=json.loads(sys.argv[1])['outputs'][0]['rms']*float(sys.argv[2]); print(f'{v:.3g}')" "$j" "$scale"
}

# fit EST NAME READ-FLAGS...: identify --save and diagnose --save on EST (exit 4, a model the
# daemon's checks refuse, still saves it); what the refinement chose, for the notes.
fit() {
    local est="$1" name="$2"
    shift 2
    "$bin" identify "$est" --save "$tmp/$name.linear.json" --json "$@" >"$tmp/$name.identify.json" 2>"$tmp/$name.identify.err" || true
    "$bin" diagnose "$est" --save "$tmp/$name.extended.json" "$@" >/dev/null 2>"$tmp/$name.diagnose.err" || true
}

# chosen NAME: the linear model's order and how it was obtained.
chosen() {
    python3 - "$tmp/$1.identify.json" <<'EOF'
import json, sys
try:
    j = json.load(open(sys.argv[1]))
except Exception:
    print("identify failed"); sys.exit()
r = j.get("refinement")
m = j["model"]
if r and r["applied"]:
    c = r["chosen"]
    s = f"output-error, order {m['order']}" + (" (integrator)" if c["integrator"] else "")
    s += f", from {c['start'].upper()}"
else:
    s = f"OKID/ERA, order {m['order']}"
print(s)
EOF
}

rows=()

if [ -f "$data/silverbox/SNLS80mV.csv" ]; then
    f="$data/silverbox/SNLS80mV.csv"
    # Data rows r (0-based) are file lines r + 2 (one header line).
    cut_rows() { awk -F, -v a="$1" -v b="$2" 'BEGIN{print "u,y"} NR>=a+2 && NR<b+2 {print $1 "," $2}' "$f"; }
    cut_rows 40650 105712 >"$tmp/sb_est.csv"
    cut_rows 105712 127400 >"$tmp/sb_ms.csv"
    cut_rows 100 40575 >"$tmp/sb_arrow.csv"
    cut_rows 100 32100 >"$tmp/sb_arrow_ne.csv"
    flags=(--input u --output y --fs 610.35)
    fit "$tmp/sb_est.csv" sb "${flags[@]}"
    lin=() ext=()
    for t in sb_ms sb_arrow sb_arrow_ne; do
        lin+=("$(rms "$tmp/sb.linear.json" "$tmp/$t.csv" 50 1000 "${flags[@]}")")
        ext+=("$(rms "$tmp/sb.extended.json" "$tmp/$t.csv" 50 1000 "${flags[@]}")")
    done
    rows+=("| Silverbox multisine / arrow full / arrow without extrapolation, mV (50) | ${lin[0]} / ${lin[1]} / ${lin[2]} | 6.96 / 14.4 / 6.58 | ${ext[0]} / ${ext[1]} / ${ext[2]} | 0.30 / 0.26 / 0.26 | $(chosen sb) |")
else
    echo "benchmarks.sh: $data/silverbox is absent: Silverbox skipped"
fi

if [ -f "$data/cascaded-tanks/dataBenchmark.csv" ]; then
    f="$data/cascaded-tanks/dataBenchmark.csv"
    awk -F, 'BEGIN{print "u,y"} NR>1 && $1 != "" {print $1 "," $3}' "$f" >"$tmp/ct_est.csv"
    awk -F, 'BEGIN{print "u,y"} NR>1 && $2 != "" {print $2 "," $4}' "$f" >"$tmp/ct_test.csv"
    flags=(--input u --output y --fs 0.25)
    fit "$tmp/ct_est.csv" ct "${flags[@]}"
    lin="$(rms "$tmp/ct.linear.json" "$tmp/ct_test.csv" 5 1 "${flags[@]}")"
    ext="$(rms "$tmp/ct.extended.json" "$tmp/ct_test.csv" 5 1 "${flags[@]}")"
    rows+=("| Cascaded Tanks, V (5) | $lin | 0.588 | $ext | 0.191 (grey-box overflow model) | $(chosen ct) |")
else
    echo "benchmarks.sh: $data/cascaded-tanks is absent: Cascaded Tanks skipped"
fi

if [ -f "$data/emps/DATA_EMPS.csv" ] && [ -f "$data/emps/DATA_EMPS_PULSES.csv" ]; then
    flags=(--input vir_force_N --output qm_position_m)
    fit "$data/emps/DATA_EMPS.csv" emps "${flags[@]}"
    lin="$(rms "$tmp/emps.linear.json" "$data/emps/DATA_EMPS_PULSES.csv" 20 1000 "${flags[@]}")"
    ext="$(rms "$tmp/emps.extended.json" "$data/emps/DATA_EMPS_PULSES.csv" 20 1000 "${flags[@]}")"
    rows+=("| EMPS, mm (20) | $lin | 5.53 | $ext | 2.64 | $(chosen emps) |")
else
    echo "benchmarks.sh: $data/emps is absent: EMPS skipped"
fi

page="$tmp/table.md"
{
    echo "Produced by \`scripts/benchmarks.sh\` from \`../shared/data\`; do not edit by hand. RMS of"
    echo "the free-run simulation of the test record (after the protocol's initialisation window"
    echo "of n samples, shown in brackets) in the benchmark's unit; every decision taken on the"
    echo "estimation record. *Published* figures: Champneys, Beintema, Tóth, Schoukens, Rogers,"
    echo "*Baseline Results for Selected Nonlinear System Identification Benchmarks* (2024)."
    echo
    echo "| benchmark (n) | propid linear | published linear state space | propid extended | best published | propid linear model |"
    echo "|---|---|---|---|---|---|"
    for r in "${rows[@]}"; do echo "$r"; done
} >"$page"
if [ -n "$out" ]; then
    cp "$page" "$out"
else
    python3 scripts/splice_docs.py benchmarks docs/benchmarks.md "$page"
fi
cat "$page"
