#!/usr/bin/env python3
"""Side by side: python-control's ERA against `propid identify` on the same CSV (issue 2 and 6).

Not run by CI. Needs numpy, scipy and control (python-control); scripts/bench_vs_python_control.sh
installs them into a virtual environment under target/.

  compare_python_control.py generate N OUT.csv [--seed S]
      writes a pulse experiment on a mass-spring-damper-like thrust response at 1 kHz
      (docs/PROTOCOL.md section 6 header `t_s,throttle,thrust_N`, throttle as the TSP/1 level
      0..10000): an operating point, one one-sample throttle pulse after 100 samples, its
      response over the rest of the record, Gaussian thrust noise (with --pulses K, K pulses
      spread evenly).
  compare_python_control.py compare FILE.csv [--propid BIN] [--order 2] [--truth FN,ZETA,DC]
      python-control: Markov parameters from the pulses (baseline-subtracted, scaled by the
      amplitude, averaged), then `control.eigensys_realization` (= `era`) with a square Hankel
      where it fits in memory; propid: `propid identify FILE --json --order N` as a whole
      process. Prints times (each one run), their ratio and fn, zeta, DC gain of both against
      the truth.

The Markov convention is propid's (docs/ARCHITECTURE.md): response to a unit input held for one
sample, no 1/dt scaling; python-control's ERA takes the same sequence, Y_0 first.
"""
import argparse
import json
import math
import subprocess
import sys
import time

import numpy as np

# The plant of the benchmark: thrust deviation y, throttle deviation u (fraction),
# y'' + 2 zeta wn y' + wn^2 y = K wn^2 u.
TRUTH = {"fn_hz": 12.0, "zeta": 0.08, "dc_gain": 8.0}
FS = 1000.0
OP_LEVEL = 5000          # operating point, TSP/1 level (0.5 throttle)
PULSE = 1000             # pulse height, TSP/1 level (0.1 throttle)
NOISE_N = 0.002          # thrust noise std, N
THRUST_OP = 4.0          # thrust at the operating point, N
LEAD = 100               # samples before the first pulse


def plant_ss(truth=TRUTH, fs=FS):
    """Exact zero-order-hold discretisation (A_d, B_d, C) of the plant."""
    from scipy.linalg import expm
    wn = 2 * math.pi * truth["fn_hz"]
    z = truth["zeta"]
    a = np.array([[0.0, 1.0], [-wn * wn, -2 * z * wn]])
    b = np.array([[0.0], [truth["dc_gain"] * wn * wn]])
    aug = np.zeros((3, 3))
    aug[:2, :2] = a
    aug[:2, 2:] = b
    e = expm(aug / fs)
    return e[:2, :2], e[:2, 2:], np.array([[1.0, 0.0]])


def generate(n, out, seed, pulses=1):
    ad, bd, c = plant_ss()
    level = np.full(n, OP_LEVEL, dtype=np.int64)
    spacing = max((n - LEAD) // max(pulses, 1), 1)
    starts = list(range(LEAD, n - 50, spacing))[:pulses]
    for i, s in enumerate(starts):
        level[s] += PULSE if i % 2 == 0 else -PULSE
    u = (level - OP_LEVEL) / 1e4
    x = np.zeros(2)
    y = np.empty(n)
    for k in range(n):
        y[k] = (c @ x)[0]
        x = ad @ x + bd[:, 0] * u[k]
    rng = np.random.default_rng(seed)
    thrust = THRUST_OP + y + NOISE_N * rng.standard_normal(n)
    t = np.arange(n) / FS
    with open(out, "w") as f:
        f.write("t_s,throttle,thrust_N\n")
        for k in range(n):
            f.write(f"{t[k]:.6f},{level[k]},{thrust[k]:.9f}\n")
    print(f"wrote {out}: {n} samples, {len(starts)} pulses, truth {TRUTH}")


def load_csv(path):
    data = np.genfromtxt(path, delimiter=",", names=True)
    t = data["t_s"]
    u = data["throttle"] / 1e4
    y = data["thrust_N"]
    return t, u, y


def markov_from_pulses(u, y, pre=50):
    """Average unit-pulse response over the one-sample pulses found at throttle edges."""
    base = np.median(u)
    idx = np.flatnonzero(np.abs(u - base) > 1e-9)
    if idx.size == 0:
        raise SystemExit("no pulse found")
    ends = list(idx[1:]) + [len(u)]
    length = min(e - s for s, e in zip(idx, ends))
    acc = np.zeros(length)
    for s in idx:
        amp = u[s] - base
        y0 = y[max(0, s - pre):s].mean() if s > 0 else y[0]
        acc += (y[s:s + length] - y0) / amp
    return acc / idx.size


def modal(poles_z, dt):
    s = np.log(poles_z.astype(complex)) / dt
    if len(s) != 2:
        return float("nan"), float("nan")
    wn2 = (s[0] * s[1]).real
    two_zwn = -(s[0] + s[1]).real
    wn = math.sqrt(max(wn2, 0.0))
    return wn / (2 * math.pi), (two_zwn / (2 * wn) if wn > 0 else float("nan"))


def python_control_era(markov, dt, order, mem_limit_gb):
    import control as ct
    l = len(markov)
    # Square Hankel: m = n block rows and columns, (l - 1) >= m + n.
    m = (l - 1) // 2
    need_gb = 3 * m * m * 8 / 1e9   # H, H shifted, and the full SVD factors, roughly
    if need_gb > mem_limit_gb:
        return None, f"skipped: square Hankel {m}x{m} needs ~{need_gb:.0f} GB"
    yy = markov.reshape(1, 1, l)
    t0 = time.perf_counter()
    # dt=True (unspecified sample time): given a numeric dt, python-control 0.10 multiplies B by
    # dt ("unit-area impulse"), which makes the DC gain wrong by the sample rate for Markov
    # parameters of a unit pulse held one sample. The sample time enters only via the poles.
    sys_d, _ = ct.eigensys_realization(yy, order, m=m, n=m, dt=True)
    elapsed = time.perf_counter() - t0
    poles = np.linalg.eigvals(sys_d.A)
    fn, zeta = modal(poles, dt)
    dc = float(np.real(np.squeeze(sys_d.dcgain())))
    return {"time_s": elapsed, "fn_hz": fn, "zeta": zeta, "dc_gain": dc,
            "hankel": f"{m}x{m}"}, None


def run_propid(binary, path, order):
    t0 = time.perf_counter()
    res = subprocess.run([binary, "identify", path, "--json", "--order", str(order)],
                         capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if res.returncode != 0:
        return None, f"propid failed ({res.returncode}): {res.stderr.strip()}"
    model = json.loads(res.stdout)["model"]
    dc = model["dc_gain"]
    if isinstance(dc, list):
        dc = dc[0]
    return {"time_s": elapsed, "fn_hz": model["fn_hz"], "zeta": model["zeta"], "dc_gain": dc,
            "hankel": f"{model.get('hankel_block_rows')}x{model.get('hankel_block_cols')}"
                      f" ({model.get('svd')})"}, None


def fmt(v, truth):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "n/a"
    return f"{v:.5g} ({100 * (v - truth) / truth:+.2f} %)"


def compare(args):
    t, u, y = load_csv(args.file)
    dt = float(np.median(np.diff(t)))
    truth = dict(TRUTH)
    if args.truth:
        fn, z, dc = (float(x) for x in args.truth.split(","))
        truth = {"fn_hz": fn, "zeta": z, "dc_gain": dc}
    t0 = time.perf_counter()
    markov = markov_from_pulses(u, y)
    prep = time.perf_counter() - t0
    pc, pc_err = python_control_era(markov, dt, args.order, args.mem_limit_gb)
    pr, pr_err = run_propid(args.propid, args.file, args.order)
    print(f"# {args.file}: {len(t)} samples at {1 / dt:.0f} Hz; Markov length {len(markov)} "
          f"(python-side pulse averaging {prep * 1e3:.1f} ms, not counted)")
    print(f"{'':14} {'python-control era':>34} {'propid identify (whole process)':>34}")
    rows = [("time", lambda r: f"{r['time_s'] * 1e3:.1f} ms"), ("hankel", lambda r: r["hankel"])]
    for key in ("fn_hz", "zeta", "dc_gain"):
        rows.append((key, lambda r, k=key: fmt(r[k], truth[k])))
    for name, f in rows:
        a = f(pc) if pc else "-"
        b = f(pr) if pr else "-"
        print(f"{name:14} {a:>34} {b:>34}")
    for who, err in (("python-control", pc_err), ("propid", pr_err)):
        if err:
            print(f"{'note':14} {who}: {err}")
    if pc and pr:
        print(f"{'ratio':14} python-control era / propid identify = {pc['time_s'] / pr['time_s']:.1f}x")
    print(f"{'truth':14} fn {truth['fn_hz']} Hz, zeta {truth['zeta']}, DC gain {truth['dc_gain']} N/throttle")
    return 0 if pr else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate")
    g.add_argument("n", type=int)
    g.add_argument("out")
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--pulses", type=int, default=1)
    c = sub.add_parser("compare")
    c.add_argument("file")
    c.add_argument("--propid", default="target/release/propid")
    c.add_argument("--order", type=int, default=2)
    c.add_argument("--truth", help="FN_HZ,ZETA,DC_GAIN (default: the generator's plant)")
    c.add_argument("--mem-limit-gb", type=float, default=4.0)
    args = ap.parse_args()
    if args.cmd == "generate":
        generate(args.n, args.out, args.seed, args.pulses)
        return 0
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
