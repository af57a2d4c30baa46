"""The label search's pruned memo (:func:`taopt.fleet.search._remember`): per dominance key
the vectors of labels the bound pruned, kept as an antichain that covers every vector
remembered (up to :data:`~taopt.fleet.search.PRUNED_PER_KEY`), and the search's optimum with
it of any size equal to the brute force's."""

from __future__ import annotations

import itertools
import random
from operator import le

import pytest

from taopt.fleet import search
from taopt.fleet.brute import brute_force, tiny_instance
from taopt.fleet.search import _remember, label_search


def _offer(gone: list[tuple], vec: tuple, count: int) -> bool:
    """What the search does with a pruned label's vector: remember it unless a vector of
    the memo is <= it (then the label was dropped before its bound)."""
    if any(all(map(le, other, vec)) for other in gone):
        return False
    _remember(gone, vec, count)
    return True


@pytest.mark.parametrize("seed", range(6))
def test_memo_is_an_antichain_covering_every_vector_remembered(seed, monkeypatch):
    """Uncapped, after every offer each vector offered has one of the memo <= it (none is
    forgotten) and no vector of the memo is <= another (the dominated ones are gone)."""
    monkeypatch.setattr(search, "PRUNED_PER_KEY", 10**6)
    rng = random.Random(seed)
    gone: list[tuple] = []
    offered = []
    dropped = 0
    for count in range(300):
        vec = tuple(float(rng.randint(0, 4)) for _ in range(3))
        offered.append(vec)
        if not _offer(gone, vec, count):
            dropped += 1
        for v in offered:
            assert any(all(map(le, other, v)) for other in gone), (v, gone)
        for a, b in itertools.permutations(gone, 2):
            assert not all(map(le, a, b)), (a, b)
    assert dropped > 0  # the memo was exercised both ways
    assert len(gone) < len(set(offered))


def test_capped_memo_keeps_at_most_the_cap_of_vectors_offered(monkeypatch):
    """Capped, the memo never holds more than the cap, only vectors offered, the last one
    offered always among them."""
    monkeypatch.setattr(search, "PRUNED_PER_KEY", 3)
    rng = random.Random(7)
    gone: list[tuple] = []
    offered = set()
    for count in range(200):
        vec = tuple(float(rng.randint(0, 9)) for _ in range(4))
        offered.add(vec)
        if _offer(gone, vec, count):
            assert vec in gone
        assert len(gone) <= 3
        assert set(gone) <= offered


def _grid() -> list[tuple]:
    """(seed, K, D, c, precedence, objective, stops): every K in {1, 2}, D and c in
    {1, 2, 3}, both precedence settings (objectives alternate), n = 3 on 2-3 stops: 36
    instances, the brute force up to 17 s on the largest."""
    out = []
    for i, (K, D, c) in enumerate(itertools.product((1, 2), (1, 2, 3), (1, 2, 3))):
        for prec in (False, True):
            objective = ("last_service", "return")[(i + prec) % 2]
            out.append((500 + 2 * i + prec, K, D, c, prec, objective, 2 + i % 2))
    return out


#: Grid instances whose search drops labels by the memo at the optimum's cut and whose
#: brute force takes about a second at most: (K, D, c, precedence).
FAST = [
    case
    for case in _grid()
    if case[1:5]
    in {
        (1, 1, 2, False),
        (1, 1, 3, True),
        (1, 3, 1, True),
        (2, 1, 1, True),
        (2, 1, 2, True),
        (2, 1, 3, False),
    }
]


def _check(case: tuple, sizes: tuple[int, ...], monkeypatch: pytest.MonkeyPatch) -> None:
    seed, K, D, c, prec, objective, stops = case
    problem = tiny_instance(seed, 3, K, D, c, prec, objective, stops=stops)
    optimum, plan, _ = brute_force(problem)
    assert plan is not None
    for size in sizes:
        monkeypatch.setattr(search, "PRUNED_PER_KEY", size)
        # at the optimum's cut most labels are pruned, so the memo is used most
        result = label_search(problem, beam=0, cutoff=optimum * (1 + 1e-6))
        assert result["stopped_by"] == "optimal"
        assert result["value"] == pytest.approx(optimum, rel=1e-9, abs=1e-9)
        free = label_search(problem, beam=0)
        assert free["value"] == pytest.approx(optimum, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("case", FAST)
def test_search_with_the_memo_of_any_size_equals_brute_force(case, monkeypatch):
    """With a memo of 1, 2 or the default vectors per key the search proves the brute-force
    optimum, at the optimum's cut and without one."""
    _check(case, (1, 2, search.PRUNED_PER_KEY), monkeypatch)


@pytest.mark.slow
@pytest.mark.parametrize("case", _grid())
def test_search_with_the_memo_equals_brute_force_on_the_grid(case, monkeypatch):
    """The same on every K, D, c of the grid (36 instances, about 2 minutes on one core)."""
    _check(case, (1, search.PRUNED_PER_KEY, 10**6), monkeypatch)
