"""Fixed-point decimal text of float arrays, byte for byte what C's `"%.{d}f"` writes, with
the digits of many numbers made at once by numpy integer arithmetic.

A number's scaled magnitude p = |x| 10^d is rounded to the nearest integer in floating
point; where p lies within p 2^-51 of a half (the float product, within half an ulp of the
exact one, could fall on either side of it) or is not a finite number below 2^49, that
number alone is formatted by Python's `%` (C's correctly rounded printf). Negative numbers,
zero included, keep their sign, as printf does ("-0.000000").
"""

from __future__ import annotations

import numpy as np

_LIMIT = float(2 ** 49)  # scaled magnitudes below it: q / 10 and q / 10^d floor exactly


def fixed_decimal_fields(values: np.ndarray, decimals: int) -> np.ndarray:
    """(W, N) uint8: column i is the i-th number of the flattened `values` as
    `"%.{decimals}f"` writes it (1 <= decimals <= 9), ASCII, right-aligned in W bytes (the
    longest text) and padded above with zero bytes. Column-major: each byte place is one
    contiguous row."""
    if not 1 <= decimals <= 9:
        raise ValueError(f"decimals must be in [1, 9], got {decimals}")
    x = np.asarray(values, dtype=float).ravel()
    scale = 10.0 ** decimals
    with np.errstate(invalid="ignore", over="ignore"):  # inf and nan fall back to printf
        p = np.abs(x) * scale
        q = np.floor(p)
        frac = p - q
        # p is within half an ulp (<= p 2^-53) of the exact product: decided past 2^-51 p
        exact = (p < _LIMIT) & (np.abs(frac - 0.5) > p * 2.0 ** -51)
    q += frac > 0.5
    q[~exact] = 0.0
    whole = np.floor(q / scale)
    part = (q - whole * scale).astype(np.int32)
    slow = np.flatnonzero(~exact)
    texts = [b"%.*f" % (decimals, v) for v in x[slow].tolist()]
    k = len(str(int(whole.max(initial=0))))  # digits of the largest whole part
    width = max([1 + k + 1 + decimals] + [len(t) for t in texts])
    dot = width - 1 - decimals
    out = np.zeros((width, len(x)), dtype=np.uint8)
    for j in range(decimals):  # the fraction's digits, last first
        np.add(part % 10, ord("0"), out=out[width - 1 - j], casting="unsafe")
        part //= 10
    out[dot] = ord(".")
    rest = whole.astype(np.int64)
    count = np.ones(len(x), dtype=np.int64)  # digits of each whole part
    for j in range(k):  # the whole part's, last first, none left of its first
        digit = rest % 10 + ord("0")
        if j:
            digit[rest == 0] = 0
            count += rest > 0
        out[dot - 1 - j] = digit
        rest //= 10
    negative = np.flatnonzero(np.signbit(x) & exact)
    out[dot - 1 - count[negative], negative] = ord("-")
    for i, text in zip(slow.tolist(), texts):
        out[:, i] = 0
        out[width - len(text):, i] = np.frombuffer(text, dtype=np.uint8)
    return out


def fixed_decimal_rows(values: np.ndarray, decimals: int, tails: np.ndarray) -> bytes:
    """The rows of the (n, m) `values`, each number `"%.{decimals}f"`, comma separated,
    each row followed by its `tails` (n,) byte string (numpy "S" dtype, e.g. b",label\r\n";
    no zero bytes), all in one bytes object."""
    n, m = np.shape(values)
    fields = fixed_decimal_fields(np.transpose(values), decimals)  # column by column
    width = len(fields)
    tails = np.ascontiguousarray(tails, dtype=bytes)
    tail = tails.view(np.uint8).reshape(n, tails.itemsize)
    rows = np.full((m * (width + 1) - 1 + tail.shape[1], n), ord(","), dtype=np.uint8)
    for c in range(m):  # byte place by byte place: each a contiguous row
        rows[c * (width + 1):c * (width + 1) + width] = fields[:, c * n:(c + 1) * n]
    rows[m * (width + 1) - 1:] = tail.T
    flat = rows.T.ravel()
    return flat[flat != 0].tobytes()
