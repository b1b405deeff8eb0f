#!/usr/bin/env bash
# MQTT load (issue 33 item 4): STANDS simulated stands at RATE Hz (`propid sim` on ptys), one
# `propid run` daemon each, all publishing through one Mosquitto broker on a free loopback port
# (models, events, stats, and the batched live samples: mqtt_samples = true), one subscriber to
# every stand's topics. Measures, over the run:
#   - CPU of the broker and of the daemons (utime + stime from /proc, % of one core over the
#     run's wall time; the daemons' as their mean and their maximum);
#   - the latency of a model line from its window to the subscriber: the daemon's own part
#     (its stats line's latency_s: the window's last sample received -> the line published)
#     plus the part after (the line on the daemon's stdout -> the same line at the subscriber,
#     both stamped by this script's one clock);
#   - messages lost: model lines on the daemons' stdout that never reached the subscriber,
#     and the daemons' mqtt_dropped.
# Prints a Markdown table for docs/mqtt.md. Run by hand once (not a test: the machine's load
# changes the numbers): scripts/mqtt_load.sh [BIN]   (STANDS=20 RATE=1000 LEVELS=12 by default)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/release/propid}
STANDS=${STANDS:-20} RATE=${RATE:-1000} LEVELS=${LEVELS:-12}
command -v mosquitto_sub >/dev/null || { echo "needs mosquitto-clients" >&2; exit 2; }
MOSQ=$(command -v mosquitto || echo /usr/sbin/mosquitto)
exec python3 - "$BIN" "$STANDS" "$RATE" "$LEVELS" "$MOSQ" <<'PY'
import json, os, socket, subprocess, sys, tempfile, threading, time, statistics

binary, stands, rate, levels, mosq = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
work = tempfile.mkdtemp(prefix="mqtt_load.")
tick = os.sysconf("SC_CLK_TCK")

def free_port():
    s = socket.socket(); s.bind(("127.0.0.1", 0)); p = s.getsockname()[1]; s.close(); return p

def cpu_s(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / tick

port = free_port()
conf = os.path.join(work, "mosquitto.conf")
with open(conf, "w") as f:
    f.write(f"listener {port} 127.0.0.1\nallow_anonymous true\nmax_queued_messages 100000\n")
broker = subprocess.Popen([mosq, "-c", conf], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
for _ in range(200):
    try:
        socket.create_connection(("127.0.0.1", port), 0.1).close(); break
    except OSError:
        time.sleep(0.05)

arrived = {}   # (stand, t_s, first_sample) -> first arrival time
arrivals = 0
samples_msgs = 0
lock = threading.Lock()
sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(port), "-q", "1", "-v",
                        "-t", "propid/+/model", "-t", "propid/+/samples", "-t", "propid/+/status"],
                       stdout=subprocess.PIPE, text=True)
def read_sub():
    global arrivals, samples_msgs
    for line in sub.stdout:
        now = time.monotonic()
        topic, _, payload = line.rstrip("\n").partition(" ")
        parts = topic.split("/")
        if len(parts) < 3 or parts[0] != "propid":
            continue  # the next lines of a samples batch (one message, several lines)
        if parts[2] == "model":
            m = json.loads(payload)
            with lock:
                arrivals += 1
                arrived.setdefault((parts[1], m["t_s"], m["first_sample"]), now)
        elif parts[2] == "samples":
            with lock:
                samples_msgs += 1
threading.Thread(target=read_sub, daemon=True).start()
time.sleep(0.5)

lv = ", ".join(f"{0.3 + 0.3 * i / max(levels - 1, 1):.3f}" for i in range(levels))
sims, daemons, published, outs = [], [], {}, {}
sim_cfg = os.path.join(work, "sim.toml")
with open(sim_cfg, "w") as f:
    f.write("[plant]\nkind = \"second_order\"\n")
for i in range(stands):
    link = os.path.join(work, f"stand{i}")
    sims.append(subprocess.Popen([binary, "sim", "--seconds", "600", "--config", sim_cfg,
                                  "--rate", str(rate), "--link", link],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
for i in range(stands):
    link = os.path.join(work, f"stand{i}")
    while not os.path.exists(link):
        time.sleep(0.02)
    cfg = os.path.join(work, f"d{i}.toml")
    with open(cfg, "w") as f:
        f.write(f"[identify]\npulses_per_model = 4\n[experiment]\nlevels = [{lv}]\nramp_ms = 100\n"
                f"settle_ms = 300\npulse_amplitudes = [0.1, 0.15]\npulse_spacing_ms = 150\n"
                f"pulses_per_level = 8\n[publish]\nmqtt = \"mqtt://127.0.0.1:{port}\"\n"
                f"stand = \"s{i}\"\nmqtt_samples = true\n")
    daemons.append(subprocess.Popen([binary, "run", "--config", cfg, "--port", link],
                                    stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True))

def read_daemon(i, p):
    lines = []
    for line in p.stdout:
        now = time.monotonic()
        v = json.loads(line)
        if v.get("type") == "model":
            published[(f"s{i}", v["t_s"], v["first_sample"])] = now
        lines.append(v)
    outs[i] = lines
readers = [threading.Thread(target=read_daemon, args=(i, p)) for i, p in enumerate(daemons)]
for r in readers: r.start()

t0 = time.monotonic()
b0 = cpu_s(broker.pid)
# the daemons' CPU is read at their end (their /proc entry goes with them): wait for each
dcpu = []
for p in daemons:
    while p.poll() is None:
        try:
            c = cpu_s(p.pid)
        except OSError:
            break
        time.sleep(0.2)
    dcpu.append(c)
wall = time.monotonic() - t0
b1 = cpu_s(broker.pid)
for r in readers: r.join()
time.sleep(2.0)
for p in sims + [sub, broker]:
    p.terminate()

stats = [next(v for v in reversed(outs[i]) if v.get("type") == "stats") for i in range(stands)]
lat_after = sorted(arrived[k] - t for k, t in published.items() if k in arrived)
lost = sum(1 for k in published if k not in arrived)
q = lambda xs, f: xs[min(len(xs) - 1, round((len(xs) - 1) * f))] if xs else float("nan")
p50d = statistics.median(s["latency_s"]["p50"] for s in stats if s["latency_s"]["p50"] is not None)
p99d = max(s["latency_s"]["p99"] for s in stats if s["latency_s"]["p99"] is not None)
print(f"| stands × rate | {stands} × {rate} Hz, {levels} operating points, samples on |")
print(f"|---|---|")
print(f"| run (wall) | {wall:.1f} s |")
print(f"| models published / reached the subscriber (unique) / lost | {len(published)} / {len(published) - lost} / {lost} |")
print(f"| model messages received (with resends) | {arrivals} |")
print(f"| samples messages received | {samples_msgs} ({samples_msgs / wall / stands:.1f} per stand per s) |")
print(f"| mqtt_dropped (sum over daemons) | {sum(s['mqtt_dropped'] for s in stats)} |")
print(f"| broker CPU | {100 * (b1 - b0) / wall:.1f} % of one core |")
print(f"| daemon CPU, mean / max | {100 * statistics.mean(dcpu) / wall:.1f} % / {100 * max(dcpu) / wall:.1f} % of one core |")
print(f"| latency window -> published (daemons' p50 median, p99 max) | {1e3 * p50d:.1f} ms / {1e3 * p99d:.1f} ms |")
print(f"| latency published -> subscriber, p50 / p99 / max | {1e3 * q(lat_after, .5):.2f} ms / {1e3 * q(lat_after, .99):.2f} ms / {1e3 * q(lat_after, 1):.2f} ms |")
PY
