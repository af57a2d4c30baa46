"""The tree's bookkeeping (issue 33, "same search, less CPU"): the rows it keeps in Python
(:class:`~taopt.models.sop_bc.CsrRows`, grown from the rows it adds itself) are HiGHS's rows
to the bit at every LP, the vectorised ``_splits`` equals the per-node loop it replaced, and
the tree with the new mechanics runs the same search as with the old ones (scipy matrices
rebuilt per product, every added row read back from HiGHS, the per-node split loop): the same
bound trace, nodes, LPs, rows and pool counts on random SOPs of 16-20 nodes."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

from taopt.models import sop_bc
from taopt.models.sop_bc import BranchCut, CsrRows, Rows, solve_sop_bc
from taopt.models.sop_cuts import SopCutModel
from taopt.sop.problem import SopProblem


def _random_sop(key: list[int], n: int, density: float) -> SopProblem:
    """A random n-node SOP (costs 0-99, start 0, end n - 1), each pair of inner nodes a
    precedence with probability ``density``."""
    rng = np.random.default_rng(key)
    cost = rng.integers(0, 100, size=(n, n)).astype(float)
    pairs = [
        (a, b) for a, b in itertools.combinations(range(1, n - 1), 2) if rng.random() < density
    ]
    return SopProblem(cost, pairs, 0, n - 1)


def _splits_reference(
    tree: BranchCut, values: np.ndarray, ones: np.ndarray, zeros: np.ndarray
) -> list[tuple[tuple[str, int], np.ndarray, np.ndarray]]:
    """The per-node loop that ``BranchCut._splits`` replaced (main before issue 33's B12)."""
    model = tree.model
    open_arc = ~model.fixed
    open_arc[zeros] = False
    found: list[tuple[float, tuple[str, int], np.ndarray, np.ndarray]] = []
    for side, ends in (("out", model.tails), ("in", model.heads)):
        positive = open_arc & (values > sop_bc.INTEGRAL)
        counts = np.bincount(ends[positive], minlength=model.n)
        counts[ends[ones]] = 0
        for v in np.flatnonzero(counts >= 2):
            arcs = np.flatnonzero(open_arc & (ends == v))
            ranked = arcs[np.argsort(-values[arcs], kind="stable")]
            total = np.cumsum(values[ranked])
            k = int(np.argmin(np.abs(total - 0.5)))
            k = min(k, len(ranked) - 2)
            found.append(
                (abs(float(total[k]) - 0.5), (side, int(v)), ranked[: k + 1], ranked[k + 1 :])
            )
    found.sort(key=lambda item: item[0])
    return [(key, first, rest) for _, key, first, rest in found]


def _estimate_reference(
    costs: sop_bc.PseudoCosts, key: tuple[str, int], shares: tuple[float, float]
) -> np.ndarray:
    """``PseudoCosts.estimate`` on numpy arrays, as before."""
    mean = np.where(costs.seen > 0, costs.total / np.maximum(costs.seen, 1), 1.0)
    counts = costs.counts.get(key)
    if counts is not None:
        own = costs.sums[key] / np.maximum(counts, 1)
        mean = np.where(counts > 0, own, mean)
    return mean * np.asarray(shares)


def _score_reference(gains: Any, value: float) -> float:
    """``_score`` by ``np.prod``, as before."""
    tiny = 1e-6 * max(abs(value), 1.0)
    return float(np.prod([min(max(float(g), 0.0), 1e12) + tiny for g in gains]))


def _append_reference(self: CsrRows, other: CsrRows) -> CsrRows:
    """``CsrRows.append`` by concatenation (main before issue 33's B17)."""
    return CsrRows(
        np.concatenate([self.indptr, other.indptr[1:] + self.indptr[-1]]).astype(np.int32),
        np.concatenate([self.indices, other.indices]),
        np.concatenate([self.data, other.data]),
        self.n,
    )


def _apply_reference(self: BranchCut, node: Any) -> tuple[np.ndarray, np.ndarray]:
    """``BranchCut._apply`` as before issue 33's B17: the last node's bounds undone in a call
    of their own, a stored basis packed whole (column statuses read into Python) and set as
    a new ``HighsBasis``."""
    model = self.model
    highs = model.highs
    self._undo()
    lower = np.zeros(model.n_arcs)
    upper = np.where(model.fixed, 0.0, 1.0)
    lower[node.ones] = 1.0
    upper[node.zeros] = 0.0
    changed = sop_bc._union(model.n_arcs, node.ones, node.zeros).astype(np.int32)
    if len(changed):
        highs.changeColsBounds(len(changed), changed, lower[changed], upper[changed])
    self._changed = changed
    stored, own, node.own = node.basis, node.own, None
    if own is not None:
        pool = self._pool()
        pool._grow(int(highs.getNumRow()))
        if own.ids is pool.ids:
            highs.setBasis(own.raw)
            self._last = node.number
            return lower, upper
        stored = node.basis = own
    if stored is not None and (own is not None or node.parent != self._last):
        packed = stored.packed()
        pool = self._pool()
        if sop_bc.POOL_REPAIR:
            self._restore(pool.missing(packed), returned=False)
        pool._grow(int(highs.getNumRow()))
        row_status = pool.statuses(packed)
        if row_status is not None:
            basis = sop_bc.highspy.HighsBasis()
            basis.col_status = [sop_bc._BY_VALUE[k] for k in packed[0].tolist()]
            basis.row_status = [sop_bc._BY_VALUE[k] for k in row_status.tolist()]
            basis.valid = True
            highs.setBasis(basis)
    self._last = node.number
    return lower, upper


def _old_mechanics(monkeypatch: Any) -> None:
    """The tree's mechanics before: a scipy matrix built for each product, the rows the tree
    adds read back from HiGHS (``Rows.now``), the per-node split loop, the pool's arrays
    compacted at each return, HiGHS's whole info record read, the pseudo-cost estimates and
    scores on numpy arrays; rows appended by concatenation, the bounds of two nodes changed
    in two calls, stored bases read whole and set as new objects."""
    monkeypatch.setattr(
        CsrRows,
        "dot",
        lambda self, x: sp.csr_matrix((self.data, self.indices, self.indptr), shape=self.shape) @ x,
    )
    monkeypatch.setattr(
        CsrRows,
        "tdot",
        lambda self, y: (
            sp.csr_matrix((self.data, self.indices, self.indptr), shape=self.shape).T @ y
        ),
    )
    monkeypatch.setattr(BranchCut, "_added", lambda self, before, more: None)
    monkeypatch.setattr(BranchCut, "_splits", _splits_reference)
    monkeypatch.setattr(sop_bc, "POOL_DEAD", 0.0)  # the pool compacted at each return
    monkeypatch.setattr(sop_bc, "TDOT_SPARSE", 0.0)  # every row multiplied
    monkeypatch.setattr(sop_bc.PseudoCosts, "estimate", _estimate_reference)
    monkeypatch.setattr(sop_bc, "_score", _score_reference)
    monkeypatch.setattr(sop_bc, "_info", lambda highs, name: getattr(highs.getInfo(), name))
    monkeypatch.setattr(CsrRows, "append", _append_reference)
    monkeypatch.setattr(BranchCut, "_apply", _apply_reference)


def _search(problem: SopProblem, nodes: int) -> dict[str, Any]:
    """What defines the search of the tree to ``nodes`` nodes."""
    result = solve_sop_bc(problem, node_limit=nodes)
    info = result.info
    keys = ("nodes", "lps", "strong_lps", "cuts", "tree_cuts", "rows_end", "pool", "open")
    keys += ("strong_iterations", "first_iterations", "strong_fixings", "max_depth")
    same = {key: info[key] for key in keys}
    same["trace"] = [bound for _, bound in info["trace"]]
    same["result"] = (result.status, result.objective, result.bound, list(result.order))
    return same


def test_csr_rows_products_and_selection_are_scipys():
    """``CsrRows``'s products, selections and appends equal scipy's on a random matrix (the
    products to the bit: the same kernels on the same arrays)."""
    rng = np.random.default_rng(7)
    dense = np.where(rng.random((40, 30)) < 0.2, rng.normal(size=(40, 30)), 0.0)
    matrix = sp.csr_matrix(dense)
    rows = CsrRows.of(matrix)
    x, y = rng.normal(size=30), rng.normal(size=40)
    assert np.array_equal(rows.dot(x), matrix @ x)
    assert np.array_equal(rows.tdot(y), matrix.T @ y)
    for share in (0.05, 0.3, 0.6):  # duals mostly zero (the rows taken alone), some -0
        sparse = np.where(rng.random(40) < share, rng.normal(size=40), 0.0)
        sparse[rng.random(40) < 0.2] = -0.0
        ours, scipys = rows.tdot(sparse), matrix.T @ sparse
        assert np.array_equal(ours.view(np.int64), scipys.view(np.int64))  # bits, signed 0
    which = rng.permutation(40)[:17]
    mask = rng.random(40) < 0.5
    for pick in (which, mask, np.zeros(0, dtype=np.int64)):
        assert (rows.take(pick).matrix() != matrix[pick]).nnz == 0
    both = rows.take(which).append(rows.take(mask))
    assert (both.matrix() != sp.vstack([matrix[which], matrix[mask]])).nnz == 0
    listed = CsrRows.lists([np.array([3, 5]), np.array([0, 29, 7])], [None, [0.5, 2.0, 1.0]], 30)
    assert np.array_equal(listed.matrix().toarray()[1, [0, 29, 7]], [0.5, 2.0, 1.0])
    assert listed.matrix().toarray()[0].sum() == 2.0


def test_append_in_place_keeps_the_rows_made_before():
    """Appends into a growable store equal concatenation, and rows made before keep their
    entries when their store is appended to again (in place) or from an older prefix (a
    copy): two branches from one base."""
    rng = np.random.default_rng(11)

    def block(rows: int) -> CsrRows:
        dense = np.where(rng.random((rows, 25)) < 0.3, rng.normal(size=(rows, 25)), 0.0)
        return CsrRows.of(sp.csr_matrix(dense))

    base = block(6)
    made = [base]
    for step in range(12):  # in place, from the newest, or from an older one (a copy)
        pick = made[-1] if step % 3 else made[int(rng.integers(len(made)))]
        more = block(int(rng.integers(0, 4)))
        grown = pick.append(more)
        expect = _append_reference(pick, more)
        for a, b in ((grown.indptr, expect.indptr), (grown.indices, expect.indices)):
            assert np.array_equal(a, b)
        assert np.array_equal(grown.data, expect.data)
        made.append(grown)
    copies = [(m.indices.copy(), m.data.copy()) for m in made]
    for m in made:  # appending to each again never changes any made before
        m.append(block(2))
    for m, (indices, data) in zip(made, copies, strict=True):
        assert np.array_equal(m.indices, indices) and np.array_equal(m.data, data)


def test_stored_basis_counts_and_sets_as_a_new_basis():
    """``_ChildBasis.basic_columns`` equals the count from its column statuses, and setting
    it (``set``: HiGHS's object with its rows replaced) leaves HiGHS with the same basis as a
    new ``HighsBasis`` of the same statuses, on LPs of random SOPs."""
    for seed in range(3):
        model = SopCutModel(_random_sop([33, 14, seed], 18, 0.15))
        model.highs.run()
        ids = np.arange(int(model.highs.getNumRow()))
        stored = sop_bc._ChildBasis(model.highs.getBasis(), ids)
        col_status, row_status, _ = stored.packed()
        assert stored.basic_columns() == int((col_status == sop_bc._BASIC).sum())
        fresh = sop_bc.highspy.HighsBasis()
        fresh.col_status = [sop_bc._BY_VALUE[k] for k in col_status.tolist()]
        fresh.row_status = [sop_bc._BY_VALUE[k] for k in row_status.tolist()]
        fresh.valid = True
        model.highs.setBasis(fresh)
        expect = model.highs.getBasis()
        model.highs.setBasis()  # the slack basis between
        stored.set(model.highs, row_status)
        got = model.highs.getBasis()
        assert sop_bc._packed(got.col_status).tolist() == sop_bc._packed(expect.col_status).tolist()
        assert sop_bc._packed(got.row_status).tolist() == sop_bc._packed(expect.row_status).tolist()
        assert (got.valid, got.alien) == (expect.valid, expect.alien)
        assert np.array_equal(stored.row_status(), row_status)  # read before the change


def test_tree_rows_are_highs_rows_at_every_lp(monkeypatch):
    """At every LP of the tree (rows leaving after 1-2 slack LPs, so the pool moves rows both
    ways), the rows it keeps (grown from the rows it added itself) are HiGHS's rows read
    whole, to the bit; many LPs took rows from Python, not from HiGHS."""
    checked = taken = 0
    bound_of = BranchCut._bound_of
    added = BranchCut._added

    def checking(self: BranchCut, lower: np.ndarray, upper: np.ndarray) -> Any:
        nonlocal checked
        out = bound_of(self, lower, upper)
        whole = Rows.of(self.model)
        rows = self._rows
        assert rows is not None and rows.count == whole.count
        for a, b in ((rows.csr.indptr, whole.csr.indptr), (rows.csr.indices, whole.csr.indices)):
            assert np.array_equal(a, b)
        assert np.array_equal(rows.csr.data, whole.csr.data)
        assert np.array_equal(rows.lower, whole.lower)
        assert np.array_equal(rows.upper, whole.upper)
        checked += 1
        return out

    def counting(self: BranchCut, before: int, more: Rows) -> None:
        nonlocal taken
        kept = self._rows
        added(self, before, more)
        taken += self._rows is not kept

    monkeypatch.setattr(BranchCut, "_bound_of", checking)
    monkeypatch.setattr(BranchCut, "_added", counting)
    for n, age in ((16, 1), (18, 1), (20, 2)):  # trees of 4-8 nodes, 50-130 LPs
        monkeypatch.setattr(sop_bc, "POOL_AGE", age)
        solve_sop_bc(_random_sop([33, 12, 1], n, 0.15), node_limit=12)
    assert checked >= 150 and taken >= 20


def test_estimates_and_scores_equal_the_numpy_ones():
    """``PseudoCosts.estimate`` and ``_score`` equal their numpy forms to the bit on random
    observations (keys seen, unseen, one child seen)."""
    rng = np.random.default_rng(3)
    costs = sop_bc.PseudoCosts()
    keys = [("out", k) for k in range(5)] + [("in", k) for k in range(5)]
    for trial in range(200):
        key = keys[int(rng.integers(len(keys)))]
        shares = (float(rng.random()), float(rng.random()))
        assert np.array_equal(costs.estimate(key, shares), _estimate_reference(costs, key, shares))
        gains = [float(g) for g in rng.normal(2.0, 3.0, size=2)]
        if trial % 7 == 0:
            gains[0] = math.inf
        value = float(rng.normal(100.0, 50.0))
        assert sop_bc._score(gains, value) == _score_reference(gains, value)
        costs.observe(key, int(rng.integers(2)), float(rng.random() * 5), float(rng.random()))


def test_vectorised_splits_equal_the_loop():
    """``_splits`` equals the per-node loop on random points of a 20-node model, with random
    arcs fixed to 0 and 1 (the same keys, F and rest, in the same order)."""
    problem = _random_sop([33, 13], 20, 0.1)
    model = SopCutModel(problem)
    tree = BranchCut(model, None)
    rng = np.random.default_rng(5)
    for trial in range(30):
        values = np.where(rng.random(model.n_arcs) < 0.3, rng.random(model.n_arcs), 0.0)
        values[rng.random(model.n_arcs) < 0.05] = 0.5  # ties
        ones = np.flatnonzero(rng.random(model.n_arcs) < 0.01 * (trial % 3))
        zeros = np.flatnonzero(rng.random(model.n_arcs) < 0.1)
        new, old = tree._splits(values, ones, zeros), _splits_reference(tree, values, ones, zeros)
        assert [key for key, _, _ in new] == [key for key, _, _ in old]
        for (_, f, r), (_, g, s) in zip(new, old, strict=True):
            assert np.array_equal(f, g) and np.array_equal(r, s)
    assert len(new) > 0


@pytest.mark.parametrize("seed,n", [(1, 16), (3, 18), (1, 20)])
def test_same_search_as_the_old_mechanics(seed, n, monkeypatch):
    """To 25 nodes on random SOPs of 16-20 nodes, the tree runs the same search with the new
    mechanics as with the old (same bound trace, nodes, LPs, rows, pool counts, simplex
    iterations, result)."""
    problem = _random_sop([33, 12, seed], n, 0.15)
    new = _search(problem, 25)
    with monkeypatch.context() as patch:
        _old_mechanics(patch)
        old = _search(problem, 25)
    assert new == old
    assert new["lps"] > new["nodes"] > 1


def test_missing_by_identity_equals_isin():
    """``CutPool.missing`` (a lookup by row identity) names the pooled rows alive whose
    identity is nonbasic in a stored basis, as ``np.isin`` does, on random pools."""
    rng = np.random.default_rng(17)
    for _ in range(200):
        next_id = int(rng.integers(1, 60))
        pooled = rng.permutation(next_id)[: int(rng.integers(1, next_id + 1))]
        pool = sop_bc.CutPool(0, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), next_id)
        pool.pooled, pool.alive = pooled, rng.random(len(pooled)) < 0.7
        ids = rng.permutation(next_id)[: int(rng.integers(0, next_id + 1))]
        row_status = np.where(rng.random(len(ids)) < 0.4, 0, sop_bc._BASIC).astype(np.int8)
        expect = np.flatnonzero(np.isin(pooled, ids[row_status != sop_bc._BASIC]) & pool.alive)
        got = pool.missing((None, row_status, ids))
        assert np.array_equal(got, expect) if pool.alive.any() else not len(got)


@pytest.mark.parametrize("runs", [0, 1, 3, 32])
def test_take_by_runs_equals_entry_by_entry(runs, monkeypatch):
    """``CsrRows.take`` of a mask copies the same arrays run by run (slices) as entry by
    entry, whatever :data:`~taopt.models.sop_bc.TAKE_RUNS` lets through."""
    rng = np.random.default_rng(19)
    monkeypatch.setattr(sop_bc, "TAKE_RUNS", runs)
    for _ in range(100):
        count = int(rng.integers(0, 30))
        dense = np.where(rng.random((count, 20)) < 0.3, rng.normal(size=(count, 20)), 0.0)
        rows = CsrRows.of(sp.csr_matrix(dense))
        mask = rng.random(count) < rng.random()
        got = rows.take(mask)
        lengths = np.diff(rows.indptr)
        entries = np.repeat(mask, lengths)
        assert np.array_equal(got.indptr, np.concatenate([[0], np.cumsum(lengths[mask])]))
        assert np.array_equal(got.indices, rows.indices[entries])
        assert np.array_equal(got.data, rows.data[entries])
        assert got.indices.dtype == np.int32 and got.indptr.dtype == np.int32
