#!/usr/bin/env bash
# The soak (issue 12 item 4): the simulated stand on a pty at 1 kHz for STAND_S seconds of stand
# time under faults (paced in real time: the pty runner keeps the device clock on the wall clock),
# with every fault kind the simulator injects on a link that stays up — bit flips (corrupted
# frames), garbage bursts, dropped samples, drop bursts of 20, stalls — and the daemon `propid run`
# reading it through one experiment plan that lasts the whole run. The faults stop after STAND_S
# (`propid sim --faults-for`); the plan ends ~20 s later in a clean tail, so the daemon has read
# every byte the faults touched when the counts are compared. Hang-ups are not in it: a device
# that resets ends the plan by design (the daemon exits 8, issue 12 item 5; tests/daemon covers
# it). It checks:
#   1. resident memory is flat after warm-up: VmRSS of the daemon sampled every second; the
#      largest value in the last half of the run is at most 1.05 x the largest value by the end
#      of the warm-up (the first WARMUP_S seconds);
#   2. every injected fault is counted by the daemon exactly: the simulator's final `sim_stats`
#      line against the daemon's final `stats` line (samples_lost = dropped + corrupted samples,
#      frames dropped = corrupted frames + garbage bursts), with no byte overrun, queue overflow
#      or reconnect that would make the comparison moot;
#   3. no window the data supported was lost: every pulse the device fired is counted, and every
#      window the plan made (levels x pulses_per_level / pulses_per_model) is identified: a
#      model, or a model the quality checks refuse (`model_unreliable`, as they refuse a few
#      without any fault: see the reference) or a failed identification, each named.
# Writes docs/soak.md and README.md between <!-- BEGIN soak --> and <!-- END soak -->
# (scripts/update_readme_tables.sh copies it again). Run by hand; it takes STAND_S + ~1 min:
#
#   nice -n 10 scripts/soak.sh [BIN]        (default target/release/propid; STAND_S=1800)
#   scripts/soak.sh --analyse DIR [BIN]     (the checks and figures again, from a kept run)
#
# Exit 1 when a check fails (the figures are still written, marked FAIL). KEEP=1 keeps the
# work directory (the simulator's and the daemon's lines, the RSS samples, the parameters).
# A clean reference (the same plant and plan recorded without faults by `propid sim --record`
# and replayed) shows how many windows the quality checks refuse when nothing is lost.
set -euo pipefail
cd "$(dirname "$0")/.."
ANALYSE=
if [ "${1:-}" = "--analyse" ]; then
  ANALYSE=$2
  shift 2
fi
BIN=${1:-target/release/propid}
KEEP=${KEEP:-}
if [ -n "$ANALYSE" ]; then
  WORK=$ANALYSE
  KEEP=1
  # shellcheck disable=SC1091
  . "$WORK/params.sh"
else
  STAND_S=${STAND_S:-1800}
  WARMUP_S=${WARMUP_S:-$((STAND_S / 10))}
  WORK=$(mktemp -d /tmp/propid-soak.XXXXXX)
fi
cleanup() {
  [ -n "${SIM_PID:-}" ] && kill "$SIM_PID" 2>/dev/null || true
  [ -n "${RUN_PID:-}" ] && kill "$RUN_PID" 2>/dev/null || true
  [ -n "$KEEP" ] || rm -rf "$WORK"
}
trap cleanup EXIT
[ -n "$KEEP" ] && echo "soak: work directory $WORK"

if [ -z "$ANALYSE" ]; then
  # The plan: 3 levels, pulses every 250 ms, as many as last STAND_S + ~20 s (a multiple of the 4
  # pulses per model).
  LEVELS=3
  PULSES=$(python3 -c "s=$STAND_S; p=int(((s+20)/$LEVELS-1)/0.25); print(max(4, p-p%4))")
  PER_MODEL=4
  cat >"$WORK/ref.toml" <<EOF
[stand]
sample_rate_hz = 1000
seed = 7
[experiment]
levels = [0.3, 0.45, 0.6]
pulses_per_level = $PULSES
pulse_spacing_ms = 250
EOF
  cat >"$WORK/sim.toml" <<EOF
[stand]
sample_rate_hz = 1000
seed = 7
[faults]
bit_flip_per_byte = 2e-5
garbage_bursts_per_s = 0.2
garbage_burst_bytes = 32
drop_sample_prob = 0.0005
drop_burst_prob = 0.00002
drop_burst_samples = 20
stalls_per_s = 0.05
stall_ms = 30
EOF
  cat >"$WORK/propid.toml" <<EOF
[device]
port = "$WORK/stand"
[identify]
pulses_per_model = $PER_MODEL
[experiment]
levels = [0.3, 0.45, 0.6]
pulses_per_level = $PULSES
pulse_spacing_ms = 250
# slack for a loaded host: a starved simulator reads the heartbeats late (its watchdog would
# trip), a starved daemon answers late; neither is what the soak measures
watchdog_ms = 5000
retry_ms = 1000
max_retries = 10
EOF

  "$BIN" sim --config "$WORK/sim.toml" --link "$WORK/stand" --seconds "$((STAND_S + 600))" \
    --faults-for "$STAND_S" >"$WORK/sim.out" 2>"$WORK/sim.err" &
  SIM_PID=$!
  for _ in $(seq 100); do [ -e "$WORK/stand" ] && break; sleep 0.1; done
  "$BIN" run --config "$WORK/propid.toml" >"$WORK/run.jsonl" 2>"$WORK/run.err" &
  RUN_PID=$!
  START=$(date +%s)
  : >"$WORK/rss.tsv"
  # The daemon ends by itself when the plan is over; then the stand is stopped (its report line).
  while kill -0 "$RUN_PID" 2>/dev/null; do
    rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$RUN_PID/status" 2>/dev/null || true)
    [ -n "$rss" ] && printf '%s\t%s\n' "$(($(date +%s) - START))" "$rss" >>"$WORK/rss.tsv"
    sleep 1
  done
  RUN_RC=0
  wait "$RUN_PID" || RUN_RC=$?
  RUN_PID=
  kill -INT "$SIM_PID" 2>/dev/null || true
  wait "$SIM_PID" || true
  SIM_PID=
  ELAPSED=$(($(date +%s) - START))
  printf 'STAND_S=%s\nWARMUP_S=%s\nLEVELS=%s\nPULSES=%s\nPER_MODEL=%s\nRUN_RC=%s\nELAPSED=%s\n' \
    "$STAND_S" "$WARMUP_S" "$LEVELS" "$PULSES" "$PER_MODEL" "$RUN_RC" "$ELAPSED" >"$WORK/params.sh"

fi

# The reference: the same plant and plan without faults, recorded and replayed.
if [ ! -s "$WORK/ref.jsonl" ]; then
  "$BIN" sim --config "$WORK/ref.toml" --record "$WORK/ref.tsp" --seconds "$((STAND_S + 120))" \
    >/dev/null
  "$BIN" replay "$WORK/ref.tsp" >"$WORK/ref.jsonl" 2>/dev/null || true
  rm -f "$WORK/ref.tsp"
fi

set +e
python3 - "$WORK" "$STAND_S" "$WARMUP_S" "$LEVELS" "$PULSES" "$PER_MODEL" "$RUN_RC" \
  "$ELAPSED" <<'PY' >"$WORK/soak.md"
import json, sys
work, stand_s, warm_s, levels, pulses, per_model, run_rc, elapsed = sys.argv[1:]
stand_s, warm_s, levels, pulses, per_model = map(int, (stand_s, warm_s, levels, pulses, per_model))
sim = next(json.loads(l) for l in open(f"{work}/sim.out") if l.startswith("{"))
lines = [json.loads(l) for l in open(f"{work}/run.jsonl") if l.startswith("{")]
stats = next(l for l in reversed(lines) if l.get("type") == "stats")
f = sim["faults"]
rss = [tuple(map(int, l.split())) for l in open(f"{work}/rss.tsv")]
t_end = rss[-1][0]
warm = max(k for t, k in rss if t <= warm_s)
late = max(k for t, k in rss if t >= t_end / 2)
first = rss[0][1]
mem_ok = late <= 1.05 * warm
drops = stats["frames_dropped"]
frames_dropped = sum(drops.values())
kinds = ", ".join(f"{k} {v}" for k, v in sorted(drops.items()))
warn = {}
for l in lines:
    if l.get("type") == "warning":
        warn[l["kind"]] = warn.get(l["kind"], 0) + 1
planned = levels * pulses // per_model
ref = [json.loads(l) for l in open(f"{work}/ref.jsonl") if l.startswith("{")]
ref_stats = next(l for l in reversed(ref) if l.get("type") == "stats")
judged = [l for l in lines if l.get("kind") in ("model_unreliable", "identification_failed")]
def outcome(l):
    why = (f"{l.get('missing_samples')} samples missing, {', '.join(l.get('reasons', []))}"
           if l["kind"] == "model_unreliable" else l.get("message", ""))
    return f"{l['kind']} at {l.get('operating_point')} (t {l.get('t_s', 0):.0f} s: {why})"
outcomes = "; ".join(outcome(l) for l in judged)
checks = [
    ("samples lost (dropped + corrupted samples)", f["dropped_samples"] + f["corrupted_samples"],
     stats["samples_lost"]),
    ("frames dropped (corrupted frames + garbage bursts)",
     f["corrupted_frames"] + f["garbage_bursts"], frames_dropped),
    ("reconnects", 0, stats["reconnects"]),
    ("device segments (boots)", sim["boots"], stats["segments"]),
    ("plan outlasted the faults (daemon run > STAND_S)", 1, int(stats["elapsed_s"] > stand_s)),
    ("bytes the host did not read in time (simulator overrun)", 0, sim["bytes_overrun"]),
    ("sampler queue overflows", 0, stats["overflows"]),
    ("pulses counted (pulses the device fired)", sim["firmware"]["pulses"], stats["pulses"]),
    ("windows identified: models + refused + failed (windows the plan made)", planned,
     stats["models"] + stats["models_unreliable"] + stats["identify_errors"]),
]
ok = mem_ok and all(a == b for _, a, b in checks)
print("Generated by `scripts/soak.sh` (run by hand, not in CI; do not edit by hand): the")
print(f"simulated stand on a pty at 1 kHz for {sim['samples_total']} samples"
      f" ({sim['samples_total'] / 1000 / 60:.1f} min of stand time, paced in real time,"
      f" faults in the first {stand_s / 60:.1f} min,"
      f" {int(elapsed) / 60:.1f} min wall) with every fault the simulator injects on a link that stays up, `propid run`"
      f" reading it. Injected: {f['corrupted_frames']} corrupted frames"
      f" ({f['corrupted_samples']} of them SAMPLEs), {f['garbage_bursts']} garbage bursts,"
      f" {f['dropped_samples']} dropped samples (single and in bursts of 20), {f['stalls']}"
      f" stalls of 30 ms."
      f" Resident memory of the daemon: {first} kB at start, largest {warm} kB by the end of"
      f" the {warm_s} s warm-up, largest {late} kB in the last half (criterion: last half"
      f" ≤ 1.05 × warm-up). Daemon exit code {run_rc};"
      f" drops by kind: {kinds}; warnings: {json.dumps(warn, sort_keys=True)};"
      f" {stats['models']} models published, {stats['models_unreliable']} refused by the quality"
      f" checks, {stats['identify_errors']} failed ({outcomes or 'none'});"
      f" the reference without faults (same plant and plan, `sim --record` + `replay`):"
      f" {ref_stats['models']} models, {ref_stats['models_unreliable']} refused,"
      f" {ref_stats['identify_errors']} failed. Result: **{'PASS' if ok else 'FAIL'}**.")
print()
print("| check | injected / expected | daemon counted | |")
print("|---|---|---|---|")
print(f"| resident memory, kB (last half vs warm-up) | ≤ {int(1.05 * warm)} | {late} |"
      f" {'ok' if mem_ok else 'FAIL'} |")
for name, a, b in checks:
    print(f"| {name} | {a} | {b} | {'ok' if a == b else 'FAIL'} |")
sys.exit(0 if ok else 1)
PY
OK=$?
set -e
cat "$WORK/soak.md"
mkdir -p docs
{ echo "# Soak"; echo; cat "$WORK/soak.md"; } >docs/soak.md
python3 - <<'PY'
import re
body = open("docs/soak.md", encoding="utf-8").read().split("\n", 2)[2].strip()
readme = open("README.md", encoding="utf-8").read()
pat = re.compile(r"(<!-- BEGIN soak -->\n)(?:.*?\n)?(<!-- END soak -->)", re.S)
if not pat.search(readme):
    raise SystemExit("README.md has no markers for soak")
open("README.md", "w", encoding="utf-8").write(pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), readme))
print("docs/soak.md and README.md (soak) updated")
PY
exit "$OK"
