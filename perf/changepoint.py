"""Change-point detection over a benchmark's history: where did a series step, and by
how much. Plain python3, standard library only.

The method is Hunter's (Fleming et al., "Hunter: Using Change Point Detection to Hunt
for Performance Regressions", ICPE 2023), itself MongoDB's use of E-Divisive means
(Matteson & James, "A Nonparametric Approach for Multiple Change Point Analysis of
Multivariate Data", JASA 2014):

1. In a segment, the candidate split is the one that maximises the energy statistic
   Q(tau) = tau (n - tau) / n * (2 mean|X - Y| - mean|X - X'| - mean|Y - Y'|), X the
   points before tau and Y those after (alpha = 1, kappa = the segment's end).
   Its position is then refined to the least-squares split within a few points of it
   (the maximum-likelihood place of one mean shift): the energy statistic finds the
   step, but near it the noise of a few points can move its maximum by one or two.
2. The candidate is kept when Welch's t-test between the two sides gives p below
   `max_pvalue` (Hunter's replacement for E-Divisive's permutation test: deterministic
   and cheap) and the medians differ by at least `min_change`; then both sides are
   split again.
3. Each kept step is re-tested against its neighbours only (the points between the
   previous and the next step); the weakest failing one is dropped until all pass.

Splits fall only between two runs (points with different run keys): several runs of
one commit are one run of the code, not a place where it changed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class Step:
    index: int       # the first point after the step
    before: float    # median of the points since the previous step
    after: float     # median of the points up to the next step
    change: float    # after / before - 1
    pvalue: float    # Welch's t-test of the two sides


def median(values: list[float]) -> float:
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


# ---- Welch's t-test -------------------------------------------------------------------


def _betacf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (modified Lentz's method)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        for num in (m * (b - m) * x / ((qam + m2) * (a + m2)),
                    -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + num * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + num / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-14:
            break
    return h


def regularized_beta(a: float, b: float, x: float) -> float:
    """I_x(a, b)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    log_front = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _betacf(a, b, x) / a
    return 1.0 - math.exp(log_front) * _betacf(b, a, 1.0 - x) / b


def welch_pvalue(x: list[float], y: list[float]) -> float:
    """Two-sided p-value of Welch's unequal-variances t-test."""
    n1, n2 = len(x), len(y)
    if n1 < 2 or n2 < 2:
        return 1.0
    m1, m2 = sum(x) / n1, sum(y) / n2
    v1 = sum((a - m1) ** 2 for a in x) / (n1 - 1) / n1
    v2 = sum((b - m2) ** 2 for b in y) / (n2 - 1) / n2
    if v1 + v2 == 0.0:
        return 1.0 if m1 == m2 else 0.0
    t = (m1 - m2) / math.sqrt(v1 + v2)
    df = (v1 + v2) ** 2 / ((v1 ** 2 / (n1 - 1) if v1 else 0.0) + (v2 ** 2 / (n2 - 1) if v2 else 0.0))
    return regularized_beta(df / 2.0, 0.5, df / (df + t * t))


# ---- E-Divisive -----------------------------------------------------------------------


def best_split(x: list[float], allowed: list[int], min_size: int) -> int | None:
    """The split tau of x (x[:tau] | x[tau:]) with the largest energy statistic, among
    the allowed positions that leave at least min_size points on each side."""
    n = len(x)
    candidates = [t for t in allowed if min_size <= t <= n - min_size]
    if not candidates:
        return None
    # Sums of |x_i - x_j| kept up to date as tau moves right by one point.
    to_left = [sum(abs(x[t] - x[i]) for i in range(t)) for t in range(n)]
    to_right = [sum(abs(x[t] - x[j]) for j in range(t + 1, n)) for t in range(n)]
    within_left, between, within_right = 0.0, 0.0, sum(to_right)
    best, best_q, wanted = None, -math.inf, set(candidates)
    for tau in range(1, n):
        moved = tau - 1  # x[moved] goes from the right side to the left
        between += to_right[moved] - to_left[moved]
        within_left += to_left[moved]
        within_right -= to_right[moved]
        if tau not in wanted:
            continue
        m = n - tau
        e = 2.0 * between / (tau * m)
        e -= 2.0 * within_left / (tau * (tau - 1)) if tau > 1 else 0.0
        e -= 2.0 * within_right / (m * (m - 1)) if m > 1 else 0.0
        q = tau * m / n * e
        if q > best_q:
            best, best_q = tau, q
    return best


def refine_split(x: list[float], tau: int, allowed: list[int], min_size: int, reach: int = 3) -> int:
    """The allowed split within `reach` points of tau with the smallest sum of squared
    deviations from each side's mean."""
    n = len(x)

    def sse(t: int) -> float:
        left, right = x[:t], x[t:]
        ml, mr = sum(left) / len(left), sum(right) / len(right)
        return sum((a - ml) ** 2 for a in left) + sum((b - mr) ** 2 for b in right)

    near = [t for t in allowed if abs(t - tau) <= reach and min_size <= t <= n - min_size]
    return min(near, key=lambda t: (sse(t), abs(t - tau))) if near else tau


def _side_stats(x: list[float], lo: int, tau: int, hi: int) -> tuple[float, float, float, float]:
    left, right = x[lo:tau], x[tau:hi]
    before, after = median(left), median(right)
    change = after / before - 1.0 if before else math.inf
    return before, after, change, welch_pvalue(left, right)


def detect(values: list[float], runs: list[object] | None = None, *, min_size: int = 4,
           max_pvalue: float = 0.001, min_change: float = 0.02) -> list[Step]:
    """Steps in a series of positive values (in time order). `runs`: a key per point
    (commit, label, ...); splits fall only where it changes. Default: every point is a
    run of its own."""
    n = len(values)
    runs = runs if runs is not None else list(range(n))
    boundaries = [i for i in range(1, n) if runs[i] != runs[i - 1]]
    found: list[int] = []
    segments = [(0, n)]
    while segments:
        lo, hi = segments.pop()
        allowed = [b - lo for b in boundaries if lo < b < hi]
        tau = best_split(values[lo:hi], allowed, min_size)
        if tau is None:
            continue
        tau = refine_split(values[lo:hi], tau, allowed, min_size)
        _, _, change, p = _side_stats(values, lo, lo + tau, hi)
        if p < max_pvalue and abs(change) >= min_change:
            found.append(lo + tau)
            segments += [(lo, lo + tau), (lo + tau, hi)]
    return _retest(values, sorted(found), max_pvalue, min_change)


def _retest(values: list[float], found: list[int], max_pvalue: float, min_change: float) -> list[Step]:
    while True:
        edges = [0] + found + [len(values)]
        steps = [Step(tau, *_side_stats(values, edges[k], tau, edges[k + 2])) for k, tau in enumerate(found)]
        failing = [s for s in steps if not (s.pvalue < max_pvalue and abs(s.change) >= min_change)]
        if not failing:
            return steps
        weakest = max(failing, key=lambda s: (s.pvalue, -abs(s.change)))
        found.remove(weakest.index)
