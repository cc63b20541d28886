#!/usr/bin/env python3
"""Line observations against the truth: is the eq. (7) covariance honest?

Usage: line_errors.py DIR PROFILE [MIN_LENGTH_M]

DIR holds, for generated rooms N of PROFILE (docs/error-budget.md, "Trusting the
odometry more", has the commands):
  w_PROFILE_N.json   irslam-sim generate --seed N --profile PROFILE --out ...
  l_PROFILE_N.jsonl  irslam-sim run --world ... --lines-out ...
  t_PROFILE_N.json   ... --truth-out ...
Every line observation (robot frame at the window's end) is compared with the true
wall or box side it is nearest to (within 0.2 rad and 0.12 m, the robot within
1.5 m of it), seen from the true pose interpolated at the observation's time (20 ms
earlier: the window closes at a scan before the control period that reports it).
Prints the RMS errors against the eq. (7) sigmas, the mean normalised error squared
(2 when the covariance is honest; diagonal terms only), and the correlation of
successive observations' errors of one surface.
"""
import bisect
import glob
import json
import math
import statistics as st
import sys


def sides(world):
    w, h = world["room"]
    s = [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0))]
    for o in world["objects"]:
        x0, y0, x1, y1 = o[:4]
        s += [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]
    return s


def seen_from(segments, pose):
    """Each side as (rho, theta) in the robot frame at pose, and its distance."""
    x, y, phi = pose
    out = []
    for a, b in segments:
        dx, dy = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dx, dy)
        if length < 0.03:
            out.append(None)
            continue
        th = math.atan2(dx, -dy)  # the direction of the side's normal (-dy, dx); the sign is settled below
        nx, ny = math.cos(th), math.sin(th)
        rho = nx * a[0] + ny * a[1]
        rr, tr = rho - (nx * x + ny * y), th - phi
        if rr < 0:
            rr, tr = -rr, tr + math.pi
        t = max(0.0, min(1.0, ((x - a[0]) * dx + (y - a[1]) * dy) / (length * length)))
        out.append((rr, math.remainder(tr, 2 * math.pi), math.hypot(a[0] + t * dx - x, a[1] + t * dy - y)))
    return out


def main():
    folder, profile = sys.argv[1], sys.argv[2]
    min_length = float(sys.argv[3]) if len(sys.argv) > 3 else 0.3
    nis, e_rho, e_th, c_rho, c_th, seq = [], [], [], [], [], []
    for path in sorted(glob.glob(f"{folder}/l_{profile}_*.jsonl")):
        n = path.rsplit("_", 1)[1].split(".")[0]
        world = json.load(open(f"{folder}/w_{profile}_{n}.json"))
        truth = json.load(open(f"{folder}/t_{profile}_{n}.json"))["trajectory"]
        times = [p[0] for p in truth]
        segments = sides(world)
        for text in open(path):
            o = json.loads(text)
            if o["length"] < min_length:
                continue
            tq = o["t"] - 0.02
            i = min(max(bisect.bisect_left(times, tq), 1), len(truth) - 1)
            a, b = truth[i - 1], truth[i]
            f = max(0.0, min(1.0, (tq - a[0]) / (b[0] - a[0]))) if b[0] > a[0] else 0.0
            pose = (a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]),
                    a[3] + f * math.remainder(b[3] - a[3], 2 * math.pi))
            best = None
            for k, s in enumerate(seen_from(segments, pose)):
                if s is None:
                    continue
                d_th = math.remainder(o["theta"] - s[1], 2 * math.pi)
                d_rho = o["rho"] - s[0]
                if abs(d_th) < 0.2 and abs(d_rho) < 0.12 and s[2] < 1.5:
                    cost = (d_rho / 0.03) ** 2 + (d_th / 0.05) ** 2
                    if best is None or cost < best[0]:
                        best = (cost, d_rho, d_th, k)
            if best is None:
                continue
            _, d_rho, d_th, k = best
            nis.append(d_rho ** 2 / o["c_rho_rho"] + d_th ** 2 / o["c_theta_theta"])
            e_rho.append(d_rho), e_th.append(d_th), c_rho.append(o["c_rho_rho"]), c_th.append(o["c_theta_theta"])
            seq.append((path, k, o["t"], d_rho, d_th))
    rms = lambda v: math.sqrt(st.mean([x * x for x in v]))
    print(f"{profile}: {len(nis)} lines; mean normalised error squared {st.mean(nis):.2f} (2 if honest), "
          f"median {st.median(nis):.2f}")
    print(f"  rho: RMS error {rms(e_rho):.4f} m, eq. (7) RMS sigma {math.sqrt(st.mean(c_rho)):.4f} m, "
          f"mean {st.mean(e_rho):+.4f} m")
    print(f"  theta: RMS error {rms(e_th):.4f} rad, eq. (7) RMS sigma {math.sqrt(st.mean(c_th)):.4f} rad, "
          f"mean {st.mean(e_th):+.4f} rad")
    pairs = [(a, b) for a, b in zip(seq, seq[1:]) if a[0] == b[0] and a[1] == b[1] and b[2] - a[2] < 5]

    def corr(j):
        xs, ys = [p[0][j] for p in pairs], [p[1][j] for p in pairs]
        mx, my = st.mean(xs), st.mean(ys)
        den = math.sqrt(sum((x - mx) ** 2 for x in xs) * sum((y - my) ** 2 for y in ys))
        return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / den if den > 0 else 0.0

    if len(pairs) > 2:
        print(f"  successive observations of one surface: {len(pairs)} pairs, error correlation "
              f"rho {corr(3):+.2f}, theta {corr(4):+.2f}")


if __name__ == "__main__":
    main()
