"""The release term of the label bound (:func:`taopt.fleet.search._release_term`): the
sortie-time term with the releases across the drones' parts and each part ordered under
them (:func:`taopt.fleet.search._sequence_end`). Checked against the best completion of
every label of tiny instances (brute force over all children, no dominance), at several
cutoffs, and the part ordering against every permutation."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from fleet.test_fleet_launch_here import _drone_only
from reference_fleet import best_completion, root_label

from taopt.fleet import search
from taopt.fleet.search import _bound, _sequence_end, _Tables

# (K, D, c) with at least two drones (the term needs two); the shapes the launch-here test
# enumerates without running out of memory
SHAPES = [(1, 2, 1), (1, 3, 1), (1, 2, 3), (2, 1, 1)]


def _check_labels(shape, prec, objective, seeds, monkeypatch) -> None:
    """At every label of tiny drone-only instances (n = 3, 3 stops), with the release term
    forced on every label (``RELEASE_FROM = 0``), the label bound at a cutoff just above the
    best completion, at it, and with none, is <= that best completion."""
    K, D, c = shape
    monkeypatch.setattr(search, "RELEASE_FROM", 0.0)
    for seed in seeds:
        p = _drone_only(seed + 100 * D + 10 * c + K, 3, K, D, c, prec, objective)
        tab = _Tables(p)
        memo: dict = {}
        best_completion(tab, root_label(p), memo)
        for label, best in memo.items():
            for cutoff in (math.inf, best * 1.01 + 1e-6, best):
                b = _bound(tab, label, cutoff)
                if cutoff > best:
                    assert b <= best * (1 + 1e-9) + 1e-9, (seed, label, cutoff, b, best)
                else:  # at the best completion's value the bound may reach it, not pass it
                    assert b <= best * (1 + 1e-9) + 1e-9 or b >= cutoff, (seed, label, b, best)


@pytest.mark.parametrize("shape", SHAPES)
def test_bound_with_releases_never_above_a_labels_best_completion(shape, monkeypatch):
    """:func:`_check_labels` with precedences, ``"last_service"`` (where the term applies)."""
    _check_labels(shape, True, "last_service", (5,), monkeypatch)


@pytest.mark.slow
@pytest.mark.parametrize("objective", ["last_service", "return"])
@pytest.mark.parametrize("prec", [False, True])
@pytest.mark.parametrize("shape", SHAPES)
def test_bound_with_releases_never_above_a_labels_best_completion_more(
    shape, prec, objective, monkeypatch
):
    """:func:`_check_labels` on more seeds, both objectives, with and without precedences."""
    _check_labels(shape, prec, objective, (6, 7, 8), monkeypatch)


def test_release_term_lifts_the_bound(monkeypatch):
    """On tiny one-truck, two-drone instances with precedences the bound with the release
    term is above the bound without it at some labels and never below it (each at a cutoff
    just above the label's best completion), and the parts' ordering stage runs."""
    lifted = 0
    ordered = 0  # bounds that ordered a part under its releases (_sequence_end)
    inner = search._sequence_end

    def counted(*args):
        nonlocal ordered
        ordered += 1
        return inner(*args)

    monkeypatch.setattr(search, "_sequence_end", counted)
    for seed in range(27, 40):
        if lifted and ordered:
            break
        p = _drone_only(seed, 3, 1, 2, 1, True, "last_service")
        if not p.precedences:
            continue
        tab = _Tables(p)
        memo: dict = {}
        best_completion(tab, root_label(p), memo)
        for label, best in memo.items():
            if math.isinf(best):
                continue
            cut = best * 1.01 + 1e-6
            monkeypatch.setattr(search, "RELEASE_FROM", 0.0)
            with_term = _bound(tab, label, cut)
            monkeypatch.setattr(search, "RELEASE_MAX_DRONES", 0)
            without = _bound(tab, label, cut)
            monkeypatch.setattr(search, "RELEASE_MAX_DRONES", 3)
            assert with_term >= without - 1e-9 or without >= cut
            lifted += with_term > without + 1e-9
    assert lifted > 0
    assert ordered > 0


@pytest.mark.parametrize("seed", range(30))
def test_sequence_end_is_the_least_order(seed):
    """:func:`_sequence_end` equals the least over every precedence-respecting order of the
    max-plus recursion (or the cutoff when every order reaches it)."""
    rng = np.random.default_rng(seed)
    p = _drone_only(seed, 5, 1, 2, 2, True, "last_service")
    tab = _Tables(p)
    n = p.n
    hop = rng.uniform(1.0, 30.0, (n, n)).tolist()
    rel = rng.uniform(0.0, 60.0, n).tolist()
    X = int(rng.integers(1, 1 << n))
    cust = [j for j in range(n) if X >> j & 1]
    best = math.inf
    for order in itertools.permutations(cust):
        at = {j: i for i, j in enumerate(order)}
        if any(at[r] > at[j] for r, j in p.precedences if r in at and j in at):
            continue
        t = rel[order[0]]
        for a, b in itertools.pairwise(order):
            t = max(t + hop[a][b], rel[b])
        best = min(best, t)
    assert _sequence_end(tab, X, rel, hop, math.inf) == pytest.approx(best, rel=1e-12)
    cut = best * 0.99
    assert _sequence_end(tab, X, rel, hop, cut) >= cut
    assert _sequence_end(tab, X, rel, hop, best + 1.0) == pytest.approx(best, rel=1e-12)
