"""The pair separation's filter (issue 33): :meth:`SopCutModel._near` leaves out only pairs
whose exact check (:meth:`SopCutModel._pair_cut`) gives no row, so the separation's rows,
their order and the recorded flows are those of checking every pair."""

from __future__ import annotations

import numpy as np
import pytest

from taopt.models import sop_cuts
from taopt.models.sop_cuts import SopCutModel
from taopt.sop.generate import random_sop


def _model(seed: int) -> SopCutModel:
    rng = np.random.default_rng([45, seed])
    n = int(rng.integers(6, 26))
    return SopCutModel(random_sop(n, float(rng.choice([0.05, 0.2, 0.4])), seed))


def _points(model: SopCutModel, rng: np.random.Generator) -> list[np.ndarray]:
    """The root LP point (rows nearly tight), it perturbed, and random sparse points."""
    root = model.root().values
    points = [root] if root is not None else []
    if root is not None:
        points.append(np.clip(root + 0.05 * rng.standard_normal(model.n_arcs), 0, 1))
    for density in (0.1, 0.3):
        points.append(rng.random(model.n_arcs) * (rng.random(model.n_arcs) < density))
    return points


@pytest.mark.parametrize("seed", range(25))
@pytest.mark.parametrize("lift_all", [False, True])
def test_filtered_separation_equals_every_pair(seed, lift_all, monkeypatch):
    """separate() with the filter and with every pair checked: the same rows, order, flows."""
    monkeypatch.setattr(sop_cuts, "LIFT_ALL", lift_all)
    model = _model(seed)
    rng = np.random.default_rng(seed)
    for values in _points(model, rng):
        filtered = model.separate(values, every=True)
        flows = model.flows.copy()
        with monkeypatch.context() as patch:
            patch.setattr(SopCutModel, "_near", lambda self, *a: np.ones(len(a[3]), dtype=bool))
            every = model.separate(values, every=True)
        assert len(filtered) == len(every)
        assert all((a == b).all() for a, b in zip(filtered, every, strict=True))
        assert np.array_equal(flows, model.flows)


@pytest.mark.parametrize("seed", range(25))
def test_a_pair_left_out_has_no_row(seed):
    """At random points and random sides of W(i, j) (not only minimum cuts), a pair that
    _near leaves out gets no row from _pair_cut."""
    model = _model(seed)
    rng = np.random.default_rng([3, seed])
    pairs, before = model.pairs, model.before
    inside = ~before[:, pairs[:, 0]].T & ~before[pairs[:, 1], :]
    left_out = 0
    for _ in range(4):
        values = rng.random(model.n_arcs) * (rng.random(model.n_arcs) < 0.4)
        support = values > 1e-9
        sides = inside & (rng.random(inside.shape) < 0.5)
        sides[np.arange(len(pairs)), pairs[:, 0]] = True
        sides[np.arange(len(pairs)), pairs[:, 1]] = False
        flows = np.zeros(len(pairs), dtype=np.int64)  # every pair past the flow threshold
        near = model._near(
            values[support], model.tails[support], model.heads[support], pairs, inside, flows, sides
        )
        left_out += int((~near).sum())
        for k in np.flatnonzero(~near):
            i, j = pairs[k]
            row = model._pair_cut(values, int(i), int(j), inside[k], 0.0, sides[k], set())
            assert row == [], (i, j)
    assert left_out  # the filter is exercised


@pytest.mark.parametrize("seed", range(25))
def test_set_arrays_match_the_candidates(seed):
    """_set_arrays' W of each set candidate and its tried test (at random flows, near the
    thresholds) are those written out per candidate."""
    model = _model(seed)
    before = model.before
    candidates = model.set_candidates()
    within, (xs_of, ys_of, sides) = model._set_arrays()
    assert len(within) == len(candidates)
    rng = np.random.default_rng([5, seed])
    model.flows = rng.choice([0.5, 1.0, 1.5, 2.0, 2.5, 3.0, np.inf], size=model.flows.shape)
    tried = model.flows[xs_of, ys_of].max(axis=1) < sides + sop_cuts.SET_TIGHT
    for k, (xs, ys, side) in enumerate(candidates):
        if side == 2:
            inside = ~before[:, xs[0]] & ~before[ys[1], :]
            skip = model.flows[xs[0], ys[1]] >= side + sop_cuts.SET_TIGHT
        else:
            inside = ~before[:, list(xs)].any(axis=1) & ~before[list(ys), :].any(axis=0)
            skip = max(model.flows[x, y] for x in xs for y in ys) >= 1 + sop_cuts.SET_TIGHT
        assert np.array_equal(within[k], inside)
        assert tried[k] == (not skip)
