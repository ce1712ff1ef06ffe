#!/usr/bin/env python3
"""Fit the polynomial coefficients of src/math/trig.rs.

Each polynomial is a minimax fit of relative error, found by Lawson's
algorithm: weighted least squares whose weights are multiplied by the
error of the last fit, which converges to the equioscillating (minimax)
solution. The fit runs in f64 on a dense grid; the coefficients are then
rounded to f32, and the Rust tests measure the error of the rounded ones.

    tools/.venv/bin/python tools/fit_trig.py   # needs numpy only
"""
import math

import numpy as np


def lawson(z, target, scale, function, degree, iterations=300):
    """Coefficients c of P minimising max |(scale * P(z) - target) / function|:
    the relative error of the whole function when target is what the
    polynomial term must add to its leading terms."""
    a = np.vander(z, degree + 1, increasing=True) * (scale / function)[:, None]
    b = target / function
    w = np.full(z.shape, 1.0 / len(z))
    for _ in range(iterations):
        root = np.sqrt(w)
        c, *_ = np.linalg.lstsq(a * root[:, None], b * root, rcond=None)
        err = np.abs(a @ c - b)
        w = w * err
        w /= w.sum()
    return c, float(np.max(np.abs(a @ c - b)))


def show(name, what, c, err):
    values = ", ".join(str(np.float32(x)) for x in c)
    print(f"{name} ({what}): [{values}]  max relative error {err:.2e}")


def main():
    n = 20001
    s = np.linspace(1e-4, 0.5, n)
    z = s * s
    c, e = lawson(z, np.arcsin(s) - s, s * z, np.arcsin(s), 4)
    show("ASIN", "asin(s) = s + s z P(z), z = s^2, s <= 1/2", c, e)
    # A little past pi/4: the reduction's rounding may leave |r| just above it.
    r = np.linspace(1e-4, math.pi / 4 * 1.002, n)
    z = r * r
    c, e = lawson(z, np.sin(r) - r, r * z, np.sin(r), 2)
    show("SIN", "sin(r) = r + r z S(z)", c, e)
    c, e = lawson(z, np.cos(r) - (1 - z / 2), z * z, np.cos(r), 2)
    show("COS", "cos(r) = 1 - z/2 + z^2 C(z)", c, e)


if __name__ == "__main__":
    main()
