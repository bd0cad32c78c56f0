#!/usr/bin/env python3
"""Fields of full Stanford dragons, and the plot of what they cost (profiles/scaling.sh).

    field.py scene N MODEL   a field of N dragons (1, 4, 10 or 20) including MODEL;
                             `field.py scene 10 models/dragon_vrip.ply.gz` is scenes/dragon_field.p3f
    field.py plot JSON       the SVG of scaling.sh's JSON rows: load, build, memory and Mrays/s
                             against the triangle count, ours beside Embree's
    field.py table JSON      the same rows as a Markdown table
"""
import json
import math
import sys

# The dragon's bounds (dragon_vrip.ply): x -0.108..0.097, y 0.053..0.197, z -0.050..0.041.
CENTRE_X, CENTRE_Z, SIZE = -0.005879, -0.004603, (0.205, 0.145, 0.092)
STEP_X, STEP_Z = 0.25, 0.15
GRIDS = {1: (1, 1), 4: (2, 2), 10: (5, 2), 20: (5, 4)}


def scene(n, model):
    cols, rows = GRIDS[n]
    width = (cols - 1) * STEP_X + SIZE[0]
    depth = (rows - 1) * STEP_Z + SIZE[2]
    # Seen from above and in front (direction (0, 0.8, 1)), far enough for the grid's width to fill
    # a 16:9 frame with a 40-degree vertical field of view, or its depth and height the frame's height.
    view = [0.0, 0.8, 1.0]
    length = math.sqrt(sum(c * c for c in view))
    view = [c / length for c in view]
    half_h = math.radians(20)
    half_w = math.atan(math.tan(half_h) * 16 / 9)
    seen_h = depth * view[1] + SIZE[1] * view[2]
    d = max(width / 2 * 1.04 / math.tan(half_w), seen_h / 2 * 1.15 / math.tan(half_h)) + depth / 2 * view[2]
    at = [0.0, 0.125, 0.0]
    eye = [at[i] + view[i] * d for i in range(3)]
    plural = "s" if n > 1 else ""
    lines = [
        f"# {n} full Stanford dragon{plural} ({n * 871414:,} triangles) on a {cols} x {rows} grid, "
        f"{STEP_X} apart in x and {STEP_Z} in z,",
        "# none overlapping; the camera frames them all. The material and light are dragon_full.p3f's.",
        "spp 0",
        "bclr 0.1 0.1 0.12",
        "v",
        "from {:.6f} {:.6f} {:.6f}".format(*eye),
        "at {:.6f} {:.6f} {:.6f}".format(*at),
        "up 0 1 0",
        "angle 40",
        "hither 0.001",
        "resolution 640 360",
        "aperture 0",
        "focal 1",
        f"l 0.260000 {0.66 + d * 0.5:.6f} {0.40 + d * 0.5:.6f} 1 1 1",
        "f 0.8 0.75 0.65 0.9 1 1 1 0.1 40 0 1",
    ]
    for j in range(rows):
        for i in range(cols):
            x = (i - (cols - 1) / 2) * STEP_X - CENTRE_X
            z = (j - (rows - 1) / 2) * STEP_Z - CENTRE_Z
            lines.append(f"include {model} translate {x:.6f} 0 {z:.6f}")
    return "\n".join(lines) + "\n"


def plot(rows):
    """Four panels side by side, each a quantity against millions of triangles, ours and Embree's."""
    panels = [
        ("load (s)", "load_s"),
        ("build (s)", "build_s"),
        ("peak memory (GB)", "peak_gb"),
        ("Mrays/s", "mrays_per_s"),
    ]
    colours = {"ours": "#1f77b4", "embree": "#d62728"}
    pw, ph, left, top = 230, 190, 50, 40
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{len(panels) * (pw + left) + 20}" '
        f'height="{ph + top + 70}" font-family="sans-serif" font-size="11">',
        '<rect width="100%" height="100%" fill="white"/>',
    ]
    xs = sorted({r["triangles"] for r in rows})
    xmax = max(xs) / 1e6
    for p, (title, key) in enumerate(panels):
        ox = 20 + p * (pw + left) + left
        values = [r[key] for r in rows if r.get(key) is not None]
        ymax = max(values) * 1.1 if values else 1.0
        out.append(f'<text x="{ox + pw / 2}" y="{top - 12}" text-anchor="middle" font-weight="bold">{title}</text>')
        out.append(f'<rect x="{ox}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#888"/>')
        for t in range(5):
            v = ymax * t / 4
            y = top + ph - ph * t / 4
            out.append(f'<text x="{ox - 4}" y="{y + 4:.1f}" text-anchor="end">{v:.3g}</text>')
            out.append(f'<line x1="{ox}" y1="{y:.1f}" x2="{ox + pw}" y2="{y:.1f}" stroke="#eee"/>')
        for x in xs:
            px = ox + pw * (x / 1e6) / xmax
            out.append(f'<text x="{px:.1f}" y="{top + ph + 14}" text-anchor="middle">{x / 1e6:.3g}</text>')
        out.append(f'<text x="{ox + pw / 2}" y="{top + ph + 30}" text-anchor="middle">million triangles</text>')
        for who, colour in colours.items():
            pts = sorted(
                (r["triangles"] / 1e6, r[key]) for r in rows if r["accel"] == who and r.get(key) is not None
            )
            if not pts:
                continue
            path = " ".join(f"{ox + pw * x / xmax:.1f},{top + ph - ph * y / ymax:.1f}" for x, y in pts)
            out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="2"/>')
            for x, y in pts:
                out.append(
                    f'<circle cx="{ox + pw * x / xmax:.1f}" cy="{top + ph - ph * y / ymax:.1f}" r="3" fill="{colour}"/>'
                )
    legend_y = top + ph + 55
    for i, (who, colour) in enumerate(colours.items()):
        x = 20 + left + i * 120
        name = "whitted (BVH8)" if who == "ours" else "Embree 3"
        out.append(f'<line x1="{x}" y1="{legend_y - 4}" x2="{x + 20}" y2="{legend_y - 4}" stroke="{colour}" stroke-width="2"/>')
        out.append(f'<text x="{x + 26}" y="{legend_y}">{name}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def table(rows):
    out = [
        "| dragons | triangles | load (s) | build ours / Embree (s) | peak memory ours / Embree (GB) "
        "| Mrays/s ours / Embree | frame ours / Embree (ms, alternated) | ours / Embree (speed) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for n in sorted({r["dragons"] for r in rows}):
        by = {r["accel"]: r for r in rows if r["dragons"] == n}
        o, e, c = by["ours"], by["embree"], by["ratio"]
        out.append(
            f"| {n} | {o['triangles']:,} | {o['load_s']:.2f} | {o['build_s']:.2f} / {e['build_s']:.2f} "
            f"| {o['peak_gb']:.2f} / {e['peak_gb']:.2f} | {o['mrays_per_s']:.2f} / {e['mrays_per_s']:.2f} "
            f"| {c['frame_ms']:.1f} / {c['embree_frame_ms']:.1f} | {c['speed_ratio']:.2f}x |"
        )
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "scene":
        sys.stdout.write(scene(int(sys.argv[2]), sys.argv[3]))
    elif len(sys.argv) == 3 and sys.argv[1] in ("plot", "table"):
        with open(sys.argv[2]) as f:
            rows = json.load(f)
        sys.stdout.write(plot(rows) if sys.argv[1] == "plot" else table(rows))
    else:
        sys.exit(__doc__)
