#!/usr/bin/env python3
"""Minimax (Remez) fits of the polynomial cores of `gough::math::Fast` (src/math/fast/*.rs).

Run: `python3 tools/minimax.py` (needs only mpmath, which ships with SymPy; `pip install mpmath`).
Prints, per kernel, the coefficients rounded to f32 with their bit patterns, in the Rust form
pasted into `src/math/fast/<kernel>.rs`, and the fit's max weighted error before rounding to f32.
The error a kernel finally has (after rounding the coefficients to f32 and evaluating in f32) is
what the Rust tests measure and what each kernel's doc states.

Degrees are the lowest whose fit error is below ~3e-7 (a few f32 ulps), so that with the f32
rounding of coefficients and arithmetic the kernels stay well inside the 2e-6 target of issue 7.

Each kernel approximates h(z) by a polynomial P(z) of degree n on [a, b], minimising
max |w(z)·(P(z) − h(z))|, where the weight w makes that the relative error of the kernel:

| kernel | kernel form on the reduced argument            | h(z)                          | z range        |
|--------|------------------------------------------------|-------------------------------|----------------|
| sin    | sin r = r + r³·P(r²)                           | (sin √z − √z)/z^1.5           | [0, (π/4)²]    |
| cos    | cos r = 1 − r²/2 + r⁴·P(r²)                    | (cos √z − 1 + z/2)/z²         | [0, (π/4)²]    |
| tan    | tan r = r + r³·P(r²)                           | (tan √z − √z)/z^1.5           | [0, (π/4)²]    |
| atan   | atan t = t + t³·P(t²)                          | (atan √z − √z)/z^1.5          | [0, tan²(π/8)] |
| asin   | asin s = s + s³·P(s²)  (acos is built on it)   | (asin √z − √z)/z^1.5          | [0, 1/4]       |
| exp    | eʳ = 1 + r + r²·P(r)                           | (eʳ − 1 − r)/r²               | [−ln2/2, ln2/2]|
| ln     | ln(1+f) = 2s + s³·P(s²), s = f/(2+f)           | (2 atanh √z − 2√z)/z^1.5      | [0, s_max²]    |

s_max = (√2 − 1)/(√2 + 1) (f ∈ [√½ − 1, √2 − 1]). The reduced-range ends are widened by 1 % so
that rounding in the argument reduction stays inside the fitted interval.
"""

import struct

from mpmath import mp, mpf, sqrt, sin, cos, tan, atan, asin, exp, atanh, pi, log, matrix, lu_solve

mp.dps = 60


def remez(h, w, a, b, n, iters=30, grid=4000):
    """Minimax polynomial of degree n for h on [a, b] with weight w. Returns (coeffs, max error)."""
    a, b = mpf(a), mpf(b)
    # Chebyshev extrema as the starting reference.
    xs = [(a + b) / 2 - (b - a) / 2 * cos(pi * i / (n + 1)) for i in range(n + 2)]
    pts = [a + (b - a) * i / grid for i in range(grid + 1)]
    hv = {}

    def H(x):
        if x not in hv:
            hv[x] = h(x)
        return hv[x]

    best = None
    for _ in range(iters):
        m = matrix(n + 2, n + 2)
        rhs = matrix(n + 2, 1)
        for i, x in enumerate(xs):
            for j in range(n + 1):
                m[i, j] = x**j
            m[i, n + 1] = (-1) ** i / w(x)
            rhs[i] = H(x)
        sol = lu_solve(m, rhs)
        c = [sol[j] for j in range(n + 1)]

        def err(x):
            p = mpf(0)
            for cj in reversed(c):
                p = p * x + cj
            return w(x) * (p - H(x))

        ev = [err(x) for x in pts]
        # Alternating extrema: split the grid at sign changes, keep the largest |e| of each run.
        runs = []
        cur = [0]
        for i in range(1, len(pts)):
            if (ev[i] >= 0) == (ev[cur[0]] >= 0):
                cur.append(i)
            else:
                runs.append(cur)
                cur = [i]
        runs.append(cur)
        ext = [max(r, key=lambda i: abs(ev[i])) for r in runs]
        while len(ext) > n + 2:
            # drop the smaller end
            if abs(ev[ext[0]]) < abs(ev[ext[-1]]):
                ext.pop(0)
            else:
                ext.pop()
        emax = max(abs(e) for e in ev)
        best = (c, emax)
        if len(ext) < n + 2:
            break
        new = [pts[i] for i in ext]
        if all(abs(p - q) < (b - a) / grid / 2 for p, q in zip(new, xs)):
            break
        xs = new
    return best


def f32(x):
    return struct.unpack("<f", struct.pack("<f", float(x)))[0]


def bits(x):
    return struct.unpack("<I", struct.pack("<f", float(x)))[0]


def show(name, c, e):
    print(f"// {name}: fit max weighted error {float(e):.3e} (before rounding to f32)")
    for i, cj in enumerate(c):
        v = f32(cj)
        print(f"const {name.upper()}{i}: f32 = {v!r}; // 0x{bits(v):08x}  ({mp.nstr(cj, 20)})")
    print()


TINY = mpf("1e-30")
W = 1.01


def odd(fn):
    """h(z) = (fn(√z) − √z)/z^1.5, continuous at 0 by evaluating at z ≥ TINY."""
    return lambda z: (fn(sqrt(max(z, TINY))) - sqrt(max(z, TINY))) / max(z, TINY) ** mpf(1.5)


def rel_odd(fn):
    """Weight making w·(P − h) the relative error of r + r³P: r³/fn(r) = z^1.5/fn(√z)."""
    return lambda z: max(z, TINY) ** mpf(1.5) / fn(sqrt(max(z, TINY)))


def main():
    q = (pi / 4) ** 2 * W
    c, e = remez(odd(sin), rel_odd(sin), 0, q, 2)
    show("sin", c, e)

    hc = lambda z: (cos(sqrt(max(z, TINY))) - 1 + max(z, TINY) / 2) / max(z, TINY) ** 2
    wc = lambda z: max(z, TINY) ** 2 / cos(sqrt(max(z, TINY)))
    c, e = remez(hc, wc, 0, q, 1)
    show("cos", c, e)

    c, e = remez(odd(tan), rel_odd(tan), 0, q, 4)
    show("tan", c, e)

    t8 = tan(pi / 8) ** 2 * W
    c, e = remez(odd(atan), rel_odd(atan), 0, t8, 3)
    show("atan", c, e)

    c, e = remez(odd(asin), rel_odd(asin), 0, mpf(0.25) * W, 3)
    show("asin", c, e)

    ln2h = log(2) / 2 * W

    def he(r):
        if abs(r) < mpf("1e-20"):
            return mpf(0.5) + r / 6
        return (exp(r) - 1 - r) / r**2

    def we(r):
        # zero weight at r = 0 (the form is exact there); keep it positive for the solver
        return max(r**2, mpf("1e-40")) / exp(r)

    c, e = remez(he, we, -ln2h, ln2h, 3)
    show("exp", c, e)

    smax = ((sqrt(2) - 1) / (sqrt(2) + 1)) ** 2 * W
    hl = lambda z: (2 * atanh(sqrt(max(z, TINY))) - 2 * sqrt(max(z, TINY))) / max(z, TINY) ** mpf(
        1.5
    )
    wl = lambda z: max(z, TINY) ** mpf(1.5) / (2 * atanh(sqrt(max(z, TINY))))
    c, e = remez(hl, wl, 0, smax, 1)
    show("ln", c, e)

    # Cody–Waite split of π/2 and ln 2 for the argument reductions: the leading parts have few
    # significant bits so that k·C1 and k·C2 are exact in f32 for the |k| the kernels accept.
    def split(v, nbits):
        m, ex = mp.frexp(v)
        hi = mp.floor(m * 2**nbits) / 2**nbits * 2**ex
        return hi

    p1 = split(pi / 2, 8)
    p2 = split(pi / 2 - p1, 8)
    p3 = split(pi / 2 - p1 - p2, 8)
    p4 = f32(pi / 2 - p1 - p2 - p3)
    print("// pi/2 = PIO2_1 + PIO2_2 + PIO2_3 + PIO2_4 (8 + 8 + 8 + 24 bits)")
    for nme, v in (("PIO2_1", p1), ("PIO2_2", p2), ("PIO2_3", p3), ("PIO2_4", p4)):
        print(f"const {nme}: f32 = {f32(v)!r}; // 0x{bits(v):08x}")
    print(f"// residual {mp.nstr(pi / 2 - p1 - p2 - p3 - mpf(p4), 5)}")
    l1 = split(log(2), 12)
    l2 = f32(log(2) - l1)
    print("// ln 2 = LN2_HI + LN2_LO (12 + 24 bits)")
    print(f"const LN2_HI: f32 = {f32(l1)!r}; // 0x{bits(l1):08x}")
    print(f"const LN2_LO: f32 = {f32(l2)!r}; // 0x{bits(l2):08x}")
    print(f"// residual {mp.nstr(log(2) - l1 - mpf(l2), 5)}")


if __name__ == "__main__":
    main()
