#!/usr/bin/env python3
"""Draws the benchmark charts as SVG, with nothing but the Python standard library.

  plot_bench.py fig7_8  STEPS.csv   OUT.svg   per-step FPS and collision time, one line per
                                              broad phase (the paper's figures 7 and 8)
  plot_bench.py scaling RESULTS.csv OUT.svg   steps/s and time per face-step against faces,
                                              log-log, one line per broad phase (and the peer)

  plot_bench.py contacts FRAMES.csv OUT.svg   intersecting triangle pairs between bodies per
                                              frame without the failsafe, and contacts per
                                              substep with it, one line per scene

STEPS.csv is what `softbake bench --csv` writes; FRAMES.csv what `contact_cases --csv=` writes; RESULTS.csv has the columns
scene,faces,broadphase,threads,steps_per_s,peak_rss_mb (bench/scaling.sh writes it).
"""
import csv
import math
import sys
from collections import OrderedDict

COLOURS = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#7f7f7f"]
PANEL_W, PANEL_H, MARGIN_L, MARGIN_B, MARGIN_T, MARGIN_R = 520, 360, 70, 50, 40, 20


def nice_ticks(lo, hi, count=5):
    if hi <= lo:
        hi = lo + 1
    raw = (hi - lo) / count
    magnitude = 10 ** math.floor(math.log10(raw))
    step = min((m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= raw), default=raw)
    first = math.floor(lo / step) * step
    ticks = []
    t = first
    while True:
        ticks.append(t)
        if t >= hi - step * 1e-9:
            return ticks
        t += step


def log_ticks(lo, hi):
    return [10 ** e for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)]


def fmt(v):
    if v == 0:
        return "0"
    if abs(v) >= 1e6:
        return f"{v / 1e6:g}M"
    if abs(v) >= 1e3:
        return f"{v / 1e3:g}k"
    return f"{v:g}"


def panel(x0, y0, spec):
    """One chart: spec has title, xlabel, ylabel, series [(name, xs, ys)], logx, logy."""
    out = []
    xs = [x for _, sx, _ in spec["series"] for x in sx]
    ys = [y for _, _, sy in spec["series"] for y in sy if y > 0 or not spec.get("logy")]
    logx, logy = spec.get("logx", False), spec.get("logy", False)
    xlo, xhi = min(xs), max(xs)
    ylo, yhi = (min(ys), max(ys)) if ys else (0, 1)
    if logx:
        xt = log_ticks(xlo, xhi)
        xlo, xhi = xt[0], xt[-1]
    else:
        xt = nice_ticks(xlo, xhi)
        xlo, xhi = xt[0], xt[-1]
    if logy:
        yt = log_ticks(ylo, yhi)
        ylo, yhi = yt[0], yt[-1]
    else:
        yt = nice_ticks(0, yhi * 1.05)
        ylo, yhi = yt[0], yt[-1]
    w = PANEL_W - MARGIN_L - MARGIN_R
    h = PANEL_H - MARGIN_T - MARGIN_B

    def px(x):
        f = (math.log10(x) - math.log10(xlo)) / (math.log10(xhi) - math.log10(xlo)) if logx \
            else (x - xlo) / (xhi - xlo)
        return x0 + MARGIN_L + f * w

    def py(y):
        if logy:
            y = max(y, ylo)
            f = (math.log10(y) - math.log10(ylo)) / (math.log10(yhi) - math.log10(ylo))
        else:
            f = (y - ylo) / (yhi - ylo)
        return y0 + MARGIN_T + (1 - f) * h

    out.append(f'<text x="{x0 + PANEL_W / 2}" y="{y0 + 22}" text-anchor="middle" '
               f'font-size="15" font-weight="bold">{spec["title"]}</text>')
    for t in xt:
        out.append(f'<line x1="{px(t):.1f}" y1="{y0 + MARGIN_T}" x2="{px(t):.1f}" '
                   f'y2="{y0 + MARGIN_T + h}" stroke="#e5e5e5"/>')
        out.append(f'<text x="{px(t):.1f}" y="{y0 + MARGIN_T + h + 16}" text-anchor="middle" '
                   f'font-size="11">{fmt(t)}</text>')
    for t in yt:
        out.append(f'<line x1="{x0 + MARGIN_L}" y1="{py(t):.1f}" x2="{x0 + MARGIN_L + w}" '
                   f'y2="{py(t):.1f}" stroke="#e5e5e5"/>')
        out.append(f'<text x="{x0 + MARGIN_L - 6}" y="{py(t) + 4:.1f}" text-anchor="end" '
                   f'font-size="11">{fmt(t)}</text>')
    out.append(f'<rect x="{x0 + MARGIN_L}" y="{y0 + MARGIN_T}" width="{w}" height="{h}" '
               f'fill="none" stroke="#444"/>')
    out.append(f'<text x="{x0 + MARGIN_L + w / 2}" y="{y0 + PANEL_H - 12}" '
               f'text-anchor="middle" font-size="12">{spec["xlabel"]}</text>')
    out.append(f'<text transform="translate({x0 + 16},{y0 + MARGIN_T + h / 2}) rotate(-90)" '
               f'text-anchor="middle" font-size="12">{spec["ylabel"]}</text>')
    for i, (name, sx, sy) in enumerate(spec["series"]):
        colour = COLOURS[i % len(COLOURS)]
        points = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in zip(sx, sy))
        out.append(f'<polyline points="{points}" fill="none" stroke="{colour}" '
                   f'stroke-width="1.6"/>')
        if spec.get("markers"):
            for x, y in zip(sx, sy):
                out.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="3" fill="{colour}"/>')
        # The legend goes in a corner the data leaves empty: spec["legend"], top-left by default.
        corner = spec.get("legend", "top-left")
        count = len(spec["series"])
        lx = x0 + MARGIN_L + (w - 130 if corner.endswith("right") else 10)
        ly = (y0 + MARGIN_T + h - 8 - 16 * (count - 1 - i) if corner.startswith("bottom")
              else y0 + MARGIN_T + 16 + 16 * i)
        out.append(f'<line x1="{lx}" y1="{ly - 4}" x2="{lx + 18}" y2="{ly - 4}" '
                   f'stroke="{colour}" stroke-width="2.5"/>')
        out.append(f'<text x="{lx + 24}" y="{ly}" font-size="12">{name}</text>')
    return out


def svg(panels, caption):
    width, height = PANEL_W * len(panels), PANEL_H + 30
    body = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'font-family="sans-serif"><rect width="100%" height="100%" fill="white"/>']
    for i, spec in enumerate(panels):
        body += panel(i * PANEL_W, 0, spec)
    body.append(f'<text x="10" y="{height - 8}" font-size="11" fill="#555">{caption}</text>')
    body.append("</svg>")
    return "\n".join(body) + "\n"


def moving_average(values, window):
    out, total = [], 0.0
    for i, v in enumerate(values):
        total += v
        if i >= window:
            total -= values[i - window]
        out.append(total / min(i + 1, window))
    return out


def fig7_8(rows, window=50):
    steps, fps, collision = OrderedDict(), OrderedDict(), OrderedDict()
    for r in rows:
        b = r["broadphase"]
        steps.setdefault(b, []).append(int(r["step"]))
        fps.setdefault(b, []).append(1000.0 / float(r["step_ms"]))
        collision.setdefault(b, []).append(sum(float(r[k]) for k in (
            "boxes_ms", "broad_phase_ms", "narrow_phase_ms", "response_ms")))
    return [
        {"title": "Steps per second (the paper's FPS)", "xlabel": "step", "legend": "top-right",
         "ylabel": "steps / s", "series": [(b, steps[b], moving_average(fps[b], window))
                                           for b in steps]},
        {"title": "Collision time per step", "xlabel": "step", "ylabel": "ms",
         "legend": "top-right",
         "series": [(b, steps[b], moving_average(collision[b], window)) for b in steps]},
    ]


def scaling(rows):
    series = OrderedDict()
    for r in rows:
        series.setdefault(r["broadphase"], []).append(
            (int(r["faces"]), float(r["steps_per_s"])))
    panels = [
        {"title": "Steps per second", "xlabel": "faces", "ylabel": "steps / s", "logx": True,
         "legend": "bottom-left",
         "logy": True, "markers": True,
         "series": [(b, [f for f, _ in v], [s for _, s in v]) for b, v in series.items()]},
        {"title": "Time per face and step", "xlabel": "faces", "ylabel": "ns", "logx": True,
         "legend": "bottom-left",
         "logy": True, "markers": True,
         "series": [(b, [f for f, _ in v], [1e9 / (s * f) for f, s in v])
                    for b, v in series.items()]},
    ]
    return panels


def contacts(rows):
    # With the failsafe, pairs count once a scene is apart: a scene that starts tangled
    # (glued_assembly) has pairs on its first frames by construction.
    pairs, load, worst_with, apart = OrderedDict(), OrderedDict(), 0, set()
    for r in rows:
        frame, scene = int(r["frame"]), r["scene"]
        if r["variant"].endswith("no failsafe"):
            pairs.setdefault(scene, ([], []))
            pairs[scene][0].append(frame)
            pairs[scene][1].append(int(r["between"]))
        else:
            if int(r["between"]) == 0:
                apart.add(scene)
            if scene in apart:
                worst_with = max(worst_with, int(r["between"]))
            load.setdefault(scene, ([], []))
            load[scene][0].append(frame)
            load[scene][1].append(float(r["contacts_per_substep"]))
    return [
        {"title": f"Pairs between bodies without the failsafe (with it: {worst_with})",
         "xlabel": "frame", "ylabel": "intersecting triangle pairs", "legend": "top-right",
         "series": [(scene, xs, ys) for scene, (xs, ys) in pairs.items()]},
        {"title": "Contacts per substep, with the failsafe", "xlabel": "frame",
         "ylabel": "contacts / substep", "legend": "top-right",
         "series": [(scene, xs, ys) for scene, (xs, ys) in load.items()]},
    ]


def main(argv):
    if len(argv) != 4 or argv[1] not in ("fig7_8", "scaling", "contacts"):
        sys.exit(__doc__)
    with open(argv[2], newline="") as f:
        rows = list(csv.DictReader(row for row in f if not row.startswith("#")))
    if not rows:
        sys.exit(f"{argv[2]}: no rows")
    if argv[1] == "fig7_8":
        panels = fig7_8(rows)
        caption = f"softbake bench, {argv[2]}: 50-step moving averages"
    elif argv[1] == "contacts":
        panels = contacts(rows)
        caption = (f"bench/contact_cases, {argv[2]}: the tests' exact checker at the end of every "
                   "frame, implicit integrator")
    else:
        panels = scaling(rows)
        caption = f"softbake bench and bullet_peer_bench, {argv[2]}"
    with open(argv[3] + ".tmp", "w") as f:
        f.write(svg(panels, caption))
    import os
    os.replace(argv[3] + ".tmp", argv[3])
    print(f"chart: {argv[3]}")


if __name__ == "__main__":
    main(sys.argv)
