#!/usr/bin/env python3
"""Does the live web page slow the daemon? (issue 13, item 5)

Replays one long recording of the simulated stand (3 levels x 3000 pulses, ~38 min of device
time at 1 kHz) through `propid replay`:
  none     without --http;
  http     with --http 127.0.0.1:0 and no browser;
  http+51  with --http and 50 event-stream clients reading everything, plus one client that
           connects and never reads (it must be dropped, counted, and slow nothing).
Each RUNS times; prints the median run time (the stats line's elapsed_s), its ratio to `none`,
the models published (must be equal in every mode), the clients dropped and what the readers
received, and the daemon's CPU time (user + system, all its threads: the server's included).
The replay runs ~500x faster than real time, so each reader takes ~15 MB/s and the
readers' own CPU shares the machine with the daemon: the worst case.

Then in real time, `propid demo --json` (the simulated stand on a pty, ~10 s) without and with
--http and the 51 clients: the latency from a window's last sample to its model line (p50, p99
of the stats line), samples lost and queue overflows, models.

usage: scripts/http_load.py [BIN] [RUNS]     (BIN defaults to target/release/propid)
"""

import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/propid"
RUNS = int(sys.argv[2]) if len(sys.argv) > 2 else 5
READERS = 50

SIM = """[experiment]
levels = [0.3, 0.45, 0.6]
pulses_per_level = 3000
"""


def reader(host, port, got, stop):
    """An event-stream client that reads everything until the stream ends."""
    s = socket.create_connection((host, port))
    s.sendall(f"GET /events HTTP/1.1\r\nHost: {host}:{port}\r\n\r\n".encode())
    n = 0
    while not stop.is_set():
        try:
            b = s.recv(1 << 16)
        except OSError:
            break
        if not b:
            break
        n += len(b)
    got.append(n)
    s.close()


def run(rec, mode):
    args = [BIN, "replay", rec] if rec else [BIN, "demo", "--json"]
    if mode != "none":
        args += ["--http", "127.0.0.1:0"]
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    got, stop, threads, idle = [], threading.Event(), [], None
    stats = None
    models = 0
    for line in p.stdout:
        d = json.loads(line)
        if d.get("kind") == "http" and mode == "http+51":
            host, port = d["url"][len("http://"):].rstrip("/").rsplit(":", 1)
            for _ in range(READERS):
                t = threading.Thread(target=reader, args=(host, int(port), got, stop))
                t.start()
                threads.append(t)
            idle = socket.create_connection((host, int(port)))
            head = f"GET /events HTTP/1.1\r\nHost: {host}:{port}\r\n\r\n"
            idle.sendall(head.encode())  # and never reads
        elif d.get("type") == "model":
            models += 1
        elif d.get("type") == "stats":
            stats = d
            break
    if mode != "none":
        p.send_signal(signal.SIGINT)  # the replay keeps its page up until Ctrl-C
    _, _, ru = os.wait4(p.pid, 0)
    p.returncode = 0
    cpu = ru.ru_utime + ru.ru_stime
    stop.set()
    for t in threads:
        t.join()
    if idle:
        idle.close()
    return stats["elapsed_s"], models, stats.get("dropped_clients", 0), sum(got), stats, cpu


def main():
    with tempfile.TemporaryDirectory() as tmp:
        cfg = os.path.join(tmp, "sim.toml")
        rec = os.path.join(tmp, "load.tsp")
        with open(cfg, "w") as f:
            f.write(SIM)
        subprocess.run([BIN, "sim", "--config", cfg, "--record", rec, "--seconds", "3000"],
                       check=True, stdout=subprocess.DEVNULL)
        size = os.path.getsize(rec)
        print(f"recording: {size / 1e6:.0f} MB; {RUNS} runs per mode, interleaved")
        res = {m: [] for m in ("none", "http", "http+51")}
        for _ in range(RUNS):
            for m in res:
                res[m].append(run(rec, m))
        base = statistics.median(r[0] for r in res["none"])
        print(f"{'mode':<8} {'median s':>9} {'ratio':>6} {'CPU s':>6} {'ratio':>6} {'models':>7} "
              f"{'dropped':>8} {'MB read/client':>15}")
        cbase = statistics.median(r[5] for r in res["none"])
        for m, rs in res.items():
            t = statistics.median(r[0] for r in rs)
            c = statistics.median(r[5] for r in rs)
            models = sorted({r[1] for r in rs})
            dropped = statistics.median(r[2] for r in rs)
            mb = statistics.median(r[3] for r in rs) / READERS / 1e6 if m == "http+51" else 0
            print(f"{m:<8} {t:>9.3f} {t / base:>6.2f} {c:>6.2f} {c / cbase:>6.2f} {','.join(map(str, models)):>7} "
                  f"{dropped:>8.0f} {mb:>15.1f}")
        print("\nreal time (propid demo):")
        live = {m: [] for m in ("none", "http+51")}
        for _ in range(RUNS):
            for m in live:
                live[m].append(run(None, m))
        print(f"{'mode':<8} {'p50 ms':>7} {'p99 ms':>7} {'lost':>5} {'overflows':>9} {'models':>7} {'dropped':>8}")
        for m, rs in live.items():
            med = lambda f: statistics.median(f(r[4]) for r in rs)
            print(f"{m:<8} {med(lambda s: s['latency_s']['p50']) * 1e3:>7.2f} "
                  f"{med(lambda s: s['latency_s']['p99']) * 1e3:>7.2f} "
                  f"{med(lambda s: s['samples_lost']):>5.0f} {med(lambda s: s['overflows']):>9.0f} "
                  f"{','.join(map(str, sorted({r[1] for r in rs}))):>7} {med(lambda s: s['dropped_clients']):>8.0f}")


if __name__ == "__main__":
    main()
