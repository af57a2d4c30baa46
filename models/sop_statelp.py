"""The root's LP re-solved per DP state: the cut rows kept, the state's ideal fixed.

Problem: the SOP of :mod:`taopt.models.sop` (cheapest Hamiltonian path ``start -> ... -> end``
respecting the precedences), searched by the DP over states ``(I, v)`` of
:mod:`taopt.models.sop_dp` (``I`` an order ideal, ``v`` its last node).

Bound. Let ``P`` be the LP of the cut model after its root loop
(:class:`taopt.models.sop_cuts.SopCutModel`: the degree rows (thesis (2.2)-(2.3)) and the
precedence path cuts, each valid for every order). Every order through a forward state
``(I, v)`` visits ``I`` first and ends that stretch at ``v``; afterwards it never returns to
``I``. So it uses

* no arc from ``U = V \\ I`` into ``I`` (the nodes of ``U`` all come after those of ``I``), and
* no arc from ``I \\ {v}`` into ``U`` (each node of ``I`` but ``v`` is followed by one of ``I``).

Fixing those arcs to 0 in ``P`` keeps every order through the state feasible, so the restricted
LP's value bounds every order through ``(I, v)`` from below. A backward state ``(F, w)``
(:func:`taopt.models.sop_dp.reversed_problem`: ``F`` an order filter visited last, ``w`` its
first node) fixes the mirror arcs: none from ``F`` into ``V \\ F``, none from ``V \\ F`` into
``F \\ {w}``. The value used is not HiGHS's objective but the Lagrangian bound of its duals
(:meth:`taopt.models.sop_cuts.SopCutModel.dual_bound`'s argument, over the arcs left free:
``c x = y^T A x + d x >= y^T b + Σ_{a free} min(d_a, 0)`` for every ``x`` of the restricted
box), rounded up to the costs' gcd, so a solver tolerance never makes it too high. A
restricted LP HiGHS proves infeasible has no order through the state (``inf``).

Why. The root LP is one relaxation for every state; fixing the ideal forces the cut
``δ^+(I)`` to be crossed exactly once, from ``v``, which the fractional root point violates
almost everywhere. Measured on prob.42 (root 230, optimum 243, the root loop run 8 s, load 5):
on the forward DP's layer 4 (462 states) the DP's own bounds reach 243 on 64 states, the
restricted LP on 436 (median 257), at 11 ms a state. It is the branch-and-bound of the issue's
item 4 with the DP's states as its nodes (equal states merged, as in the anytime tree search
of Libralesso et al. 2020) and the root's LP re-optimised per node.

Inherited prices. Any sign-clipped duals ``y`` of the rows bound any restricted LP, so the
duals of the LP solved at a state ``k`` bound the restricted LP of each of its descendants
(their fixed arcs include ``k``'s). For the orders through a descendant that extend its kept
prefix ``p`` (every order through the state costs at least the cheapest of these, ``p`` being
the cheapest prefix of its state), ``c x = y^T A x + d x >= y^T b + Σ_{a ∈ p} d_a +
Σ_{a free, a ∉ p, d_a < 0} d_a = B_k + Σ_{a ∈ p} max(d_a, 0)``, ``B_k`` the Lagrangian bound of
``k``'s LP (the arcs of ``p`` are free in it). The DP adds ``max(d_a, 0)`` of each arc as a
state grows (:meth:`taopt.models.sop_dp._Run._inherited`), so one LP bounds a whole subtree.
With it, prob.42 with its optimum 243 as the incumbent closed (the DP ended and returned the
order of cost 243) in 27 s at load 5-7 and in 64 s at load 9 (1,972 states kept, 3,856
LPs); the DP alone kept 1.6 million states in 60 s without ending. On ry48p.1 (few
precedences: 33 nodes open after the start) the LPs dropped 41 % of their states and the
layers still grew 6-10x (60 s, load 7).

Cheaper solves. Two changes leave every bound and every drop decision as it was
(tests/sop/test_sop_statelp.py checks both against the full LP on tiny SOPs):

* *Stop at the cutoff.* A state is dropped once its bound reaches the DP's cutoff ``UB - tol``,
  and any clipped duals give a valid bound; HiGHS's dual simplex keeps its duals feasible and
  its dual objective rises to the optimum, so it is told to stop once that objective passes
  :meth:`StateLp.stop_at` (``objective_bound``). The Lagrangian bound of the duals it stopped
  at is then read as always; if it falls short of the cutoff (HiGHS's own objective is on
  perturbed costs) the LP goes on to its optimum from there.
* *Start from the ancestor's basis.* A state's LP differs from the LP of the ancestor whose
  prices it inherits by the arcs about the few nodes added since; the ancestor's optimal basis
  (kept beside its prices) is primal infeasible at most on them and dual feasible, a few dual
  simplex pivots from the state's optimum. The last LP solved, the warm start before, belongs
  to an unrelated state of the layer.

On prob.42 with its optimum as the incumbent (root loop to its end, then the DP with the LP per
state alone, main and this code alternated, load 4.3-5.9): 66-68 simplex
iterations an LP before, 14.4 after (1,156 of the 2,425 LPs stopped at the cutoff); 12.1-12.4
CPU seconds before, 7.0-7.6 after (18.7-21.4 s of wall time before, 10.6-13.8 after). What is
left is HiGHS's fixed cost per ``run`` (about 1 ms with nothing changed) and the refactorisation
after ``setBasis``. Neither the order of a layer's LPs (grouped by ancestor, by ideal) nor
skipping ``setBasis`` between siblings changed the CPU time measurably (7.4-7.8 s).

References
----------
Thesis (2.2)-(2.3), (2.5), (5.7). Ascheuer, Jünger, Reinelt, "A branch & cut algorithm for
the asymmetric traveling salesman problem with precedence constraints", Comput. Optim. Appl.
17 (2000). Libralesso, Bouhassoun, Cambazard, Jost, "Tree search for the sequential ordering
problem", ECAI 2020.
"""

from __future__ import annotations

import math
import time
from typing import Any

import highspy
import numpy as np
import scipy.sparse as sp

from taopt.runtime import MARGIN, Deadline

__all__ = [
    "FIRST_SECONDS",
    "MIN_SHARE",
    "SHARE",
    "StateLp",
    "TRIAL",
    "clipped_duals",
    "constraint_matrix",
]

#: Each state's LP starts from the optimal basis of the ancestor whose prices it inherits
#: (module docstring, "Cheaper solves"; False: from the last LP's basis, as before).
PARENT_BASIS = True

#: Seconds an LP is taken to cost before one was timed.
FIRST_SECONDS = 0.02

#: Share of a DP run's limit the LPs may use in all (:meth:`StateLp.budget`). With the LP on
#: every state the DP's layers on prob.42 grew 1.1-1.5x a layer (optimum as incumbent, load 5);
#: once the LPs stopped at half the time they grew 2-5x.
SHARE = 0.8

#: After :data:`TRIAL` LPs, the LPs stop for good when they dropped under :data:`MIN_SHARE`
#: of their states (where the root's LP already sees the ideals, they only cost time).
TRIAL = 50

#: Least share of their states the first :data:`TRIAL` LPs must drop for the LPs to go on.
MIN_SHARE = 0.1


def constraint_matrix(lp: Any) -> sp.csc_matrix:
    """The row matrix ``A`` of a ``highspy.HighsLp`` (rows x columns), whichever of its two
    formats HiGHS keeps it in: column-wise as the cut model passes it, row-wise as HiGHS may
    leave it after an LP it stopped (a 380-node stand-in's root loop cut by its time)."""
    data = (
        np.asarray(lp.a_matrix_.value_),
        np.asarray(lp.a_matrix_.index_),
        np.asarray(lp.a_matrix_.start_),
    )
    shape = (lp.num_row_, lp.num_col_)
    if lp.a_matrix_.format_ == highspy.MatrixFormat.kRowwise:
        return sp.csr_matrix(data, shape=shape).tocsc()
    return sp.csc_matrix(data, shape=shape)


def clipped_duals(
    duals: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Row duals made valid for a Lagrangian bound, and each row's side times its dual.

    ``y >= 0`` prices a row's finite lower side and ``y <= 0`` its finite upper side (a dual
    of the wrong sign for the sides a row has is clipped to 0); an equality row keeps its
    dual, any sign. With these ``y``, ``sum(constant) + sum(min(c - A^T y, 0) * x_max)`` is
    at most the LP's value for any ``y`` (weak duality), so clipping never overstates the
    bound."""
    equal = lower == upper
    positive = np.where(np.isfinite(lower), np.maximum(duals, 0.0), 0.0)
    negative = np.where(np.isfinite(upper), np.minimum(duals, 0.0), 0.0)
    y = np.where(equal, duals, positive + negative)
    constant = np.where(
        equal,
        duals * np.where(equal, lower, 0.0),
        positive * np.where(np.isfinite(lower), lower, 0.0)
        + negative * np.where(np.isfinite(upper), upper, 0.0),
    )
    return y, constant


class StateLp:
    """The restricted LP of the module docstring on a root cut model.

    Parameters
    ----------
    model : SopCutModel
        The root stage's model (:meth:`taopt.models.sop_cuts.SopCutModel.root` run); its
        column bounds are restored after every LP, its rows are not touched.
    share : float
        Share of a DP run's limit the LPs may use in all (:data:`SHARE`; the portfolio's proof
        stage, where the LPs are the work, gives them all of it).
    """

    def __init__(self, model: Any, share: float = SHARE) -> None:
        self.model = model
        #: Share of a DP run's limit the LPs may use in all (:meth:`budget`).
        self.share = share
        self.n = model.n
        self.index = np.arange(model.n_arcs, dtype=np.int32)
        self.lower = np.zeros(model.n_arcs)
        #: Seconds per LP, the mean of those timed.
        self.rate = FIRST_SECONDS
        #: LPs solved, states they dropped, seconds spent.
        self.solved = 0
        self.dropped = 0
        self.seconds = 0.0
        #: Whether some column bound is the last state's (:meth:`release` restores them).
        self.changed = False
        self._matrix: tuple[Any, np.ndarray, np.ndarray] | None = None
        #: The last LP's unrounded bound and its arcs' reduced costs ``d`` (None: no LP
        #: optimum), for :meth:`positive`.
        self.last_prices: tuple[float, np.ndarray] | None = None
        #: The most seconds all the LPs may take (:meth:`budget`); None: no limit.
        self.allowance: float | None = None
        #: HiGHS's ``objective_bound`` as last set (:meth:`_stop_at`).
        self._objective_bound = math.inf
        #: LPs HiGHS stopped at :meth:`stop_at`, and those of them then run to their optimum.
        self.stopped = 0
        self.resumed = 0
        #: Simplex iterations of all the LPs.
        self.iterations = 0

    def budget(self, seconds: float | None) -> None:
        """Let the LPs take :attr:`share` (default :data:`SHARE`) of ``seconds`` (a DP run's
        limit) in all."""
        self.allowance = None if seconds is None else self.seconds + self.share * seconds

    def failed(self) -> bool:
        """Whether the LPs stopped for good: after :data:`TRIAL` LPs they dropped under
        :data:`MIN_SHARE` of their states (:meth:`layer`)."""
        return self.solved >= TRIAL and self.dropped < MIN_SHARE * self.solved

    def usable(self) -> bool:
        """Whether the model is an LP with duals to read (not turned into the MIP)."""
        return not self.model.is_mip

    def bound(
        self,
        held: np.ndarray,
        last: int,
        reverse: bool,
        deadline: Deadline,
        cutoff: float | None = None,
        basis: Any = None,
    ) -> float:
        """The bound of state ``(held, last)`` (``held``: ``n`` bools, the ideal, or the filter
        when ``reverse``); ``-inf`` when the LP did not end (deadline).

        ``cutoff`` (the DP's ``UB - tol``): HiGHS's dual simplex may stop as soon as its dual
        objective passes :meth:`stop_at` (``objective_bound``); the Lagrangian bound of its
        duals then is returned when it reaches ``cutoff`` (the state is dropped: any clipped
        duals give a valid bound, :func:`clipped_duals`), and otherwise the LP goes on to its
        optimum from where it stopped, so the value is the optimum's as without ``cutoff``.
        ``basis``: a basis to start from (an ancestor state's optimal one, :meth:`layer`);
        None: the last LP's."""
        model = self.model
        tails, heads = model.tails, model.heads
        in_tail, in_head = held[tails], held[heads]
        if reverse:  # suffix F entered once, at `last`; never left
            zero = (in_tail & ~in_head) | (~in_tail & in_head & (heads != last))
        else:  # prefix I left once, from `last`; never entered again
            zero = (~in_tail & in_head) | (in_tail & ~in_head & (tails != last))
        zero |= model.fixed
        upper = np.where(zero, 0.0, 1.0)
        began = time.perf_counter()
        highs = model.highs
        # the bounds stay until the next state's (the last LP's basis is a warm start for it);
        # :meth:`release` restores them
        highs.changeColsBounds(model.n_arcs, self.index, self.lower, upper)
        self.changed = True
        if basis is not None:
            highs.setBasis(basis)
        left = deadline.remaining()
        if left is None:  # no limit: none left over from an earlier run either
            highs.setOptionValue("time_limit", math.inf)
        else:  # HiGHS's limit is on its run time summed over the object's runs
            spent = float(highs.getRunTime())
            highs.setOptionValue("time_limit", spent + max(left - MARGIN, 0.001))
        self._stop_at(None if cutoff is None else self.stop_at(cutoff))
        highs.run()
        self.iterations += highs.getInfo().simplex_iteration_count
        status = highs.getModelStatus()
        if status == highspy.HighsModelStatus.kObjectiveBound:
            self.stopped += 1
            value = self._dual_bound(zero)
            if cutoff is None or not value >= cutoff:  # short of it: the LP to its optimum
                self.resumed += 1
                self._stop_at(None)
                highs.run()
                self.iterations += highs.getInfo().simplex_iteration_count
                status = highs.getModelStatus()
        if status == highspy.HighsModelStatus.kInfeasible:
            value = math.inf
        elif status == highspy.HighsModelStatus.kObjectiveBound:
            pass  # stopped past the cutoff: its value is the bound read above
        elif status != highspy.HighsModelStatus.kOptimal:
            value = -math.inf
        else:
            value = self._dual_bound(zero)
        if not math.isfinite(value):
            self.last_prices = None
        spent = time.perf_counter() - began
        self.solved += 1
        self.seconds += spent
        self.rate = self.seconds / self.solved
        return value

    def stop_at(self, cutoff: float) -> float:
        """The dual objective past which no LP need go on for a state to reach ``cutoff``:
        with integral costs (the model's ``step``), a value above ``cutoff - step`` rounds
        up to ``cutoff`` or more (by :meth:`~taopt.models.sop_cuts.SopCutModel.round_up`'s
        tolerance; a value short of it is caught after the LP, :meth:`bound`)."""
        step = self.model.step
        return cutoff - step + 1e-5 if step else cutoff

    def _stop_at(self, value: float | None) -> None:
        """Set HiGHS's ``objective_bound`` (None: none), only when it changes."""
        value = math.inf if value is None else value
        if value != self._objective_bound:
            self.model.highs.setOptionValue("objective_bound", value)
            self._objective_bound = value

    def _rows(self) -> tuple[Any, np.ndarray, np.ndarray]:
        """The model's rows (``A^T`` as CSR, lower and upper sides), read once: the DP adds
        none."""
        if self._matrix is None:
            lp = self.model.highs.getLp()
            matrix = constraint_matrix(lp)
            self._matrix = (
                matrix.T.tocsr(),
                np.asarray(lp.row_lower_, dtype=float),
                np.asarray(lp.row_upper_, dtype=float),
            )
        return self._matrix

    def _dual_bound(self, zero: np.ndarray) -> float:
        """``y^T b + Σ_{a free} min(d_a, 0)`` of the last LP's duals, signs clipped as in
        :meth:`taopt.models.sop_cuts.SopCutModel.dual_bound`, rounded up to the costs' gcd;
        ``-inf`` without duals."""
        solution = self.model.highs.getSolution()
        if not solution.dual_valid:
            return -math.inf
        duals = np.asarray(solution.row_dual, dtype=float)
        transposed, lower, upper = self._rows()
        if len(duals) != len(lower):
            return -math.inf
        y, sides = clipped_duals(duals, lower, upper)
        reduced = self.model.costs - transposed @ y
        value = float(sides.sum() + np.minimum(reduced[~zero], 0.0).sum())
        self.last_prices = (value, reduced)
        return float(self.model.round_up(value))

    def positive(self, reduced: np.ndarray, reverse: bool) -> np.ndarray:
        """``max(d, 0)`` of the arcs as an ``n x n`` matrix read in the search's direction
        (transposed when ``reverse``; 0 off the model's arcs)."""
        matrix = np.zeros((self.n, self.n))
        matrix[self.model.tails, self.model.heads] = np.maximum(reduced, 0.0)
        return np.ascontiguousarray(matrix.T) if reverse else matrix

    def release(self) -> None:
        """Give the model its own column bounds back (0 on its fixed arcs, 1 elsewhere) and
        no ``objective_bound``."""
        self._stop_at(None)
        if self.changed:
            model = self.model
            upper = np.where(model.fixed, 0.0, 1.0)
            model.highs.changeColsBounds(model.n_arcs, self.index, self.lower, upper)
            self.changed = False

    def layer(
        self,
        members: np.ndarray,
        last: np.ndarray,
        total: np.ndarray,
        below: float,
        reverse: bool,
        deadline: Deadline,
        starts: list[Any] | None = None,
    ) -> tuple[np.ndarray, dict[int, tuple[float, np.ndarray, Any]]]:
        """Per state of a layer (``members``: ``(states, n)`` bools), the restricted LP's bound
        (``-inf`` where not solved), and per state solved and kept its LP's unrounded bound and
        ``max(d, 0)`` (:meth:`positive`). The states of highest bound so far go first, while the
        LPs fit in their allowance (:meth:`budget`) and, after :data:`TRIAL` LPs, while they
        drop at least :data:`MIN_SHARE` of their states.

        ``starts``: per state, the optimal basis of the ancestor whose prices it inherits
        (None: none); each LP starts from it (:data:`PARENT_BASIS`), and each kept state's
        own optimal basis is returned beside its prices for its descendants."""
        out = np.full(len(last), -np.inf)
        prices: dict[int, tuple[float, np.ndarray, Any]] = {}
        highs = self.model.highs
        for k in np.argsort(-total, kind="stable"):
            if self.allowance is not None and self.seconds + self.rate > self.allowance:
                break
            if self.failed():
                break
            if deadline.expired(MARGIN):
                break
            start = starts[k] if starts is not None and PARENT_BASIS else None
            out[k] = self.bound(members[k], int(last[k]), reverse, deadline, below, start)
            if out[k] >= below:
                self.dropped += 1
            elif self.last_prices is not None:
                positive = self.positive(self.last_prices[1], reverse)
                kept = highs.getBasis() if PARENT_BASIS else None
                prices[int(k)] = (self.last_prices[0], positive, kept)
        return out, prices
