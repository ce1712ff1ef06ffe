#!/usr/bin/env python3
"""Draw a `strata render --timeline` trace as a PNG, for docs and reports.

    python3 -m venv tools/.venv-docs
    tools/.venv-docs/bin/pip install -r tools/requirements-docs.txt
    tools/.venv-docs/bin/python tools/timeline_png.py trace.json timeline.png

One row per track of the trace: the main thread on top (load, BVH build,
setup, each pass, the film update after it, output), then one row per
worker, each work item a box coloured by the share of all the items' time
spent in shorter items (pale yellow for the shortest, through green and
blue, to dark purple for the longest), so that each colour covers as much
of the picture as any other and items of different cost look different
however the costs are spread; a hairline parts neighbouring boxes, and
idle gaps stay white. Below them, the rays-per-second counter and a key
with the times the colours stand for. Perfetto (https://ui.perfetto.dev)
opens the same file interactively; this is its still picture.
"""

import argparse
import bisect
import json
import math
import sys


def pillow():
    """Pillow's drawing modules, imported only to draw (the colour scale
    is tested without them: tests/suite/timeline_picture.rs)."""
    try:
        from PIL import Image, ImageDraw, ImageFont
    except ImportError:
        sys.exit(
            "error: timeline_png.py needs Pillow: python3 -m venv tools/.venv-docs && "
            "tools/.venv-docs/bin/pip install -r tools/requirements-docs.txt"
        )
    return Image, ImageDraw, ImageFont

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


# Short to long: viridis reversed, a ramp whose steps a reader sees as
# equal, and whose ends differ in lightness too (it survives greyscale).
RAMP = [(253, 231, 37), (94, 201, 98), (33, 145, 140), (59, 82, 139), (68, 1, 84)]


class ItemScale:
    """Work item durations to colours, by the share of all the items' time
    spent in shorter items: 0 (pale) for the shortest, 1 (dark) for the
    longest, and each part of the ramp covering as much of the picture's
    boxes as any other, so neighbours of different cost differ however the
    costs are spread. Two scales that did not: one of duration itself (pale
    at the median item, dark red at 10x and more) painted every item dark
    red where most of the time went to items ten times the cheapest; one of
    rank put all of those in the last quarter where most items are cheap."""

    def __init__(self, durations):
        self.sorted = sorted(max(d, 0.0) for d in durations) or [0.0]
        self.before = [0.0]
        for d in self.sorted:
            self.before.append(self.before[-1] + d)
        self.total = self.before[-1]

    def position(self, duration):
        """The share of the items' time in items shorter than `duration`,
        with half of that in items as long."""
        if self.total <= 0:
            return 0.5
        lo = bisect.bisect_left(self.sorted, duration)
        hi = bisect.bisect_right(self.sorted, duration)
        same = self.before[hi] - self.before[lo]
        return min(max((self.before[lo] + same / 2) / self.total, 0.0), 1.0)

    def quantile(self, q):
        """The duration of the item at which a share q of the time is spent."""
        k = bisect.bisect_left(self.before, q * self.total, 1)
        return self.sorted[min(k, len(self.sorted)) - 1]

    def colour(self, duration):
        return ramp(self.position(duration))


def ramp(x):
    """The colour at x in [0, 1] along RAMP."""
    x = min(max(x, 0.0), 1.0) * (len(RAMP) - 1)
    i = min(int(x), len(RAMP) - 2)
    f = x - i
    a, b = RAMP[i], RAMP[i + 1]
    return tuple(round(p + (q - p) * f) for p, q in zip(a, b))


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
    Image, ImageDraw, ImageFont = pillow()
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
    scale = ItemScale([e["dur"] for e in items])

    font = ImageFont.load_default()
    left, right, top = 90, 20, 34
    row = 16 if len(tids) <= 40 else 8
    counter_h = 70
    legend_h = 56
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
            colour = scale.colour(e["dur"])
            # A hairline of background between neighbours wide enough to
            # keep one, so that two alike items still read as two.
            if x1 - x0 >= 3:
                x1 -= 1
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
    # The work items' key: the ramp, with the item times at which 0, 25,
    # 50, 75 and 100% of the items' time is spent.
    y += 16
    d.text((left, y - 1), "work item:", fill=INK, font=font)
    x, bar = left + 80, 400
    for k in range(bar):
        d.line([(x + k, y), (x + k, y + 10)], fill=ramp(k / (bar - 1)))
    for q in (0.0, 0.25, 0.5, 0.75, 1.0):
        label = duration_label(scale.quantile(q))
        width = d.textlength(label, font=font)
        d.text((x + q * (bar - width), y + 12), label, fill=INK, font=font)
    d.text(
        (x + bar + 12, y - 1),
        "coloured by the share of all items' time spent in shorter items (0, 25, 50, 75, 100%)",
        fill=INK,
        font=font,
    )
    return image


def duration_label(us):
    if us >= 1e3:
        return f"{us / 1e3:.3g} ms"
    return f"{us:.3g} us"


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
