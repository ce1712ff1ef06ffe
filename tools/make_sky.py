#!/usr/bin/env python3
"""Write scenes/sky.hdr: a small procedural lat-long sky for the
environment-lit scenes (scenes/env-sky.toml) and tools/bench_mitsuba.py.

    python3 tools/make_sky.py [OUT.hdr]

128 x 64 texels in Mitsuba's envmap layout (row 0 is straight up, +y;
column u = atan2(x, -z) / 2pi): a blue sky brightening towards the
horizon, a darker ground below it, and a sun of a few texels, 35 degrees
up, whose texels are 500 times the sky's. Written as Radiance HDR with flat
(uncompressed) RGBE scanlines, which every reader takes. No dependencies.
"""

import math
import os
import sys

W, H = 128, 64
SUN = (0.62, 55.0)  # (u, angle from +y in degrees): 35 degrees above the horizon
SUN_RADIUS = 2.5  # degrees


def texel(i, j):
    u, v = (i + 0.5) / W, (j + 0.5) / H
    theta, phi = math.pi * v, 2 * math.pi * u
    d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
    st, sp = math.radians(SUN[1]), 2 * math.pi * SUN[0]
    s = (math.sin(st) * math.sin(sp), math.cos(st), -math.sin(st) * math.cos(sp))
    if math.degrees(math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, s)))))) < SUN_RADIUS:
        return (500.0, 460.0, 400.0)
    if d[1] < 0:
        return (0.12, 0.10, 0.08)
    # Brighter and whiter towards the horizon.
    t = 1.0 - d[1]
    return (0.25 + 0.45 * t, 0.45 + 0.35 * t, 0.9 + 0.1 * t)


def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes(4)
    mant, e = math.frexp(m)  # m = mant * 2^e, mant in [0.5, 1)
    f = mant * 256.0 / m
    return bytes([int(c[0] * f), int(c[1] * f), int(c[2] * f), e + 128])


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "scenes", "sky.hdr")
    data = bytearray(f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {H} +X {W}\n".encode())
    for j in range(H):
        for i in range(W):
            data += rgbe(texel(i, j))
    with open(out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
