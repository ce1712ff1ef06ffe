#!/usr/bin/env python3
"""Draw a `strata render --timeline` trace as a PNG, for docs and reports.

    python3 -m venv tools/.venv-docs
    tools/.venv-docs/bin/pip install -r tools/requirements-docs.txt
    tools/.venv-docs/bin/python tools/timeline_png.py trace.json timeline.png

One row per track of the trace: the main thread on top (load, BVH build,
setup, each pass, the film update after it, output), then one row per
worker, each work item a box coloured by its duration against the median
item's (pale: as long as the median or shorter; dark red: 10x and more,
on a log scale), so that long items and idle gaps stand out. Below them,
the rays-per-second counter. Perfetto (https://ui.perfetto.dev) opens the
same file interactively; this is its still picture.
"""

import argparse
import json
import math
import sys

try:
    from PIL import Image, ImageDraw, ImageFont
except ImportError:
    sys.exit(
        "error: timeline_png.py needs Pillow: python3 -m venv tools/.venv-docs && "
        "tools/.venv-docs/bin/pip install -r tools/requirements-docs.txt"
    )

PHASE_COLOURS = {
    "load": (76, 120, 168),
    "BVH build": (245, 133, 24),
    "setup": (157, 157, 157),
    "pass": (205, 215, 228),
    "film": (228, 87, 86),
    "after pass": (178, 121, 162),
    "output": (84, 162, 75),
}
BACKGROUND = (255, 255, 255)
INK = (40, 40, 40)
GRID = (225, 225, 225)


def phase_colour(name):
    for key, colour in PHASE_COLOURS.items():
        if name == key or name.startswith(key + " "):
            return colour
    return (120, 120, 120)


def item_colour(duration, median):
    """Pale yellow at or below the median, dark red at 10x it (log scale)."""
    x = 0.0 if median <= 0 else math.log10(max(duration / median, 1.0))
    x = min(x, 1.0)
    pale, dark = (253, 231, 160), (165, 15, 21)
    return tuple(round(p + (d - p) * x) for p, d in zip(pale, dark))


def nice_step(span, ticks):
    raw = span / max(ticks, 1)
    power = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 5, 10):
        if m * power >= raw:
            return m * power
    return 10 * power


def time_label(us):
    if us >= 1e6:
        return f"{us / 1e6:g} s"
    return f"{us / 1e3:g} ms"


def load_trace(path):
    try:
        with open(path, encoding="utf-8") as f:
            trace = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"error: {path}: {e}")
    events = trace.get("traceEvents") if isinstance(trace, dict) else trace
    if not isinstance(events, list):
        sys.exit(f"error: {path}: no traceEvents list: not a trace of strata render --timeline")
    return events


def draw(events, width, title):
    names = {e["tid"]: e["args"]["name"] for e in events if e.get("name") == "thread_name"}
    spans = [e for e in events if e.get("ph") == "X"]
    counters = sorted(
        (e["ts"], next(iter(e["args"].values()))) for e in events if e.get("ph") == "C"
    )
    if not spans:
        sys.exit("error: the trace has no spans")
    tids = sorted({e["tid"] for e in spans} | set(names))
    t0 = min(e["ts"] for e in spans)
    t1 = max(e["ts"] + e["dur"] for e in spans)
    items = [e for e in spans if e["name"] == "work item"]
    durations = sorted(e["dur"] for e in items)
    median = durations[len(durations) // 2] if durations else 0.0

    font = ImageFont.load_default()
    left, right, top = 90, 20, 34
    row = 16 if len(tids) <= 40 else 8
    counter_h = 70
    legend_h = 40
    height = top + row * len(tids) + 30 + counter_h + legend_h
    image = Image.new("RGB", (width, height), BACKGROUND)
    d = ImageDraw.Draw(image)
    plot_w = width - left - right
    x_of = lambda t: left + (t - t0) / max(t1 - t0, 1e-9) * plot_w

    d.text((left, 8), title, fill=INK, font=font)
    step = nice_step(t1 - t0, 8)
    tick = math.ceil(t0 / step) * step
    bottom = top + row * len(tids)
    while tick <= t1:
        x = x_of(tick)
        d.line([(x, top), (x, bottom + 4)], fill=GRID)
        d.text((x - 12, bottom + 6), time_label(tick - t0), fill=INK, font=font)
        tick += step
    for i, tid in enumerate(tids):
        y = top + i * row
        d.text((6, y + row / 2 - 6), names.get(tid, f"track {tid}"), fill=INK, font=font)
    for e in spans:
        i = tids.index(e["tid"])
        y0, y1 = top + i * row + 1, top + (i + 1) * row - 2
        x0, x1 = x_of(e["ts"]), x_of(e["ts"] + e["dur"])
        if e["name"] == "work item":
            colour = item_colour(e["dur"], median)
        else:
            colour = phase_colour(e["name"])
        d.rectangle([x0, y0, max(x1, x0 + 0.5), y1], fill=colour)
        if e["tid"] == 0 and x1 - x0 > 60:
            d.text((x0 + 3, y0 + 1), e["name"], fill=INK, font=font)

    # The counter: rays per second over the render.
    c_top = bottom + 24
    if counters:
        peak = max(v for _, v in counters) or 1.0
        d.text((6, c_top), "Mrays/s", fill=INK, font=font)
        d.text((6, c_top + 14), f"peak {peak:.3g}", fill=INK, font=font)
        d.line([(left, c_top + counter_h - 10), (width - right, c_top + counter_h - 10)], fill=GRID)
        points = [
            (x_of(t), c_top + counter_h - 10 - v / peak * (counter_h - 16)) for t, v in counters
        ]
        d.line(points, fill=(31, 119, 180), width=2)

    # The legend.
    y = height - legend_h + 8
    x = left
    for name, colour in PHASE_COLOURS.items():
        d.rectangle([x, y, x + 12, y + 10], fill=colour)
        d.text((x + 16, y - 1), name, fill=INK, font=font)
        x += 22 + 7 * len(name)
    y += 16
    x = left
    for label, ratio in (("work item: median or less", 1.0), ("3x", 3.0), ("10x the median", 10.0)):
        d.rectangle([x, y, x + 12, y + 10], fill=item_colour(ratio * median, median))
        d.text((x + 16, y - 1), label, fill=INK, font=font)
        x += 22 + 7 * len(label)
    return image


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("trace", help="a trace from strata render --timeline (.json)")
    parser.add_argument("png", help="the picture to write (.png)")
    parser.add_argument("--width", type=int, default=1400, help="pixels (default 1400)")
    parser.add_argument("--title", default=None, help="a line above the picture")
    args = parser.parse_args()
    if not args.png.lower().endswith(".png"):
        parser.error(f"{args.png}: the picture must be a .png")
    if args.width < 300:
        parser.error("--width must be at least 300")
    events = load_trace(args.trace)
    title = args.title or next(
        (e["args"]["name"] for e in events if e.get("name") == "process_name"), args.trace
    )
    draw(events, args.width, title).save(args.png)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
