"""Our branch-and-cut tree (:mod:`taopt.models.sop_bc`) in two processes: a peer process
takes open nodes from this one, both search, and this one proves.

Why
---
The machine the issue measures has two cores. Where the SOP portfolio sends its tree first
(:func:`taopt.models.sop.tree_first`), CP-SAT's circuit bound stays far below the root's
(prob.42 180 against 230, ft53.1 5,931 against 7,189 at 60 s) and its worker held the second
core for the whole run while the tree searched on one. Here that core searches the same tree.

How
---
The peer is a process started with "spawn" (HiGHS's threads do not survive a fork) that
builds the same :class:`~taopt.models.sop_cuts.SopCutModel` of the problem while this
process runs its root; it then gets the model's rows (the degree rows are rebuilt, every cut
row is sent as its arcs, side and weights), the arcs fixed at the root and the best order,
and waits for nodes. Nodes travel as (bound, depth, ones, zeros): a node is the set of orders
using every arc of ``ones`` and none of ``zeros`` (the module doc of
:mod:`~taopt.models.sop_bc`), whatever the rows of the LP that bounds it, so a node moves
between the two models without changing its bound's validity. Every row either side adds
holds for every order (or every order better than the best one, and both sides share the
best one), so each side's rows are its own business.

The protocol (one duplex pipe; each side reads the other's messages in the order sent):

* ``("order", cost, order)``: a better order; the reader takes it as its own best.
* ``("want",)``: the sender's open list is empty. The reader sends back half its open
  nodes (every other one, best first) as ``("nodes", k, batch)`` once it has two or more.
* ``("bound", b, got)`` from the peer, after each node it takes: the least bound of its
  open nodes and the node it is solving (``inf`` when idle), with ``got`` the last batch
  number it has taken in.
* ``("stop",)`` to the peer: it answers ``("left", b, got, counts)`` and ends.

**The bound this process proves** is ``min`` of its own open nodes, the peer's last
reported bound, and the least bound of every batch sent that the peer had not yet taken
when it reported (the batches are numbered; a report names the last one taken). A node is
always in one of these three places, so every better order lies in a node counted there.
The tree is closed when this process's list is empty, the peer reported an empty list, and
no batch is in flight; orders the peer sent before that report were read before it.

The peer process runs with one solver thread and dies with this process
(:func:`taopt.runtime.workers.become_worker`); it is always stopped and reaped by
:meth:`Peer.close`.
"""

from __future__ import annotations

import contextlib
import heapq
import math
import os
import queue
import threading
import time
from typing import Any

import numpy as np

from taopt.runtime import Deadline
from taopt.runtime.deadline import CancelToken
from taopt.runtime.workers import PipedWorker
from taopt.sop.problem import SopProblem

__all__ = [
    "PEER_STOP_GRACE",
    "PEER_STOP_WAIT",
    "SHARE_ROWS",
    "SPLIT",
    "SPLIT_MIN_CORES",
    "Link",
    "Peer",
    "split_wanted",
]

#: Whether our tree searches in two processes where the portfolio lets it (:func:`split_wanted`).
SPLIT = True

#: Cores the machine must have for the split (one per process).
SPLIT_MIN_CORES = 2

#: Seconds this process waits for the peer's last answer (``left``) after ``stop``; without
#: it the peer's last report and the batches in flight still bound its nodes.
PEER_STOP_WAIT = 1.0

#: Whether each side sends the other the rows it separates (the 0/1 rows of
#: ``SopCutModel.add_cuts``; each holds for every order): the other side adds the new ones
#: between two nodes, as its own separation would.
SHARE_ROWS = True

#: Seconds past the peer's own limit that this side waits for its last answer, and for its
#: end after that answer (then it is killed).
PEER_STOP_GRACE = 0.2

#: Seconds between two looks at the pipe while a side waits for nodes.
IDLE_POLL = 0.01


def split_wanted() -> bool:
    """Whether to start a peer: :data:`SPLIT` on a machine of :data:`SPLIT_MIN_CORES` cores,
    unless this process is a pool's worker (``TAOPT_SOLVER_THREADS=1``,
    :data:`taopt.runtime.workers.ONE_THREAD_ENV`)."""
    # a pool's worker: the pool is the parallelism
    if os.environ.get("TAOPT_SOLVER_THREADS") == "1":
        return False
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return SPLIT and (cores or 1) >= SPLIT_MIN_CORES


def _wire(node: Any) -> tuple[float, int, np.ndarray, np.ndarray]:
    """A node as sent: (bound, depth, ones, zeros); its basis stays behind."""
    return (float(node.bound), -int(node.depth_key), node.ones, node.zeros)


class Link:
    """One side's end of the pipe, kept by its :class:`~taopt.models.sop_bc.BranchCut`
    (``tree.link``): :meth:`poll` at each loop head, :meth:`idle` when its list is empty,
    :meth:`outside` in its bound. ``main``: this is the proving side (else the peer)."""

    def __init__(self, conn: Any, main: bool) -> None:
        self.conn = conn
        self.main = main
        #: The peer's last reported bound (main side; ``inf``: nothing there yet).
        self.peer_bound = math.inf
        #: Batches sent and not yet taken, by number: their least bound.
        self.flight: dict[int, float] = {}
        self.sent = 0  # batches sent
        self.got = 0  # batches taken in
        self.wanted = False  # the other side asked for nodes
        self.asked = False  # this side asked and got nothing yet
        self.stopped = False  # peer side: told to stop
        self.shared: float = math.inf  # the cost of the last order sent
        self.given = 0  # nodes sent
        self.taken = 0  # nodes taken in
        self.gone = False  # the pipe broke (the other process ended)
        self.closed = False  # main side: the peer's last answer (``left``) was read
        #: Main side: every node sent (as sent), taken back if the peer process is lost.
        self.lent: list[tuple[float, int, np.ndarray, np.ndarray]] = []
        #: Main side: the peer process ended without its last answer (its nodes taken back).
        self.lost = False
        self.reported: tuple[float, int] | None = None  # peer side: the last report sent
        self.closing = False  # main side: ``stop`` was sent, no node leaves any more
        #: Seconds this side waited for nodes (:meth:`idle`).
        self.waited = 0.0
        #: The model's cut rows up to here were sent or came from the other side.
        self._outbox: queue.Queue[tuple[Any, ...] | None] = queue.Queue()
        self._pump: threading.Thread | None = None  # the sending thread, started on first use
        self.rows_seen = -1
        self.rows_sent = 0  # cut rows sent
        self.rows_taken = 0  # cut rows taken in

    def counts(self) -> dict[str, Any]:
        """This side's part of the exchange: nodes given and taken, seconds waited, rows
        sent and taken in."""
        return {
            "given": self.given,
            "taken": self.taken,
            "waited": round(self.waited, 3),
            "rows_sent": self.rows_sent,
            "rows_taken": self.rows_taken,
        }

    # ------------------------------------------------------------------ messages
    def send(self, message: tuple[Any, ...]) -> None:
        """Queue ``message`` for this side's sending thread: a send never blocks the search
        (a pipe's buffer holds a few hundred kB; two sides each blocked in a send to the
        other, neither reading, would never end)."""
        if self.gone:
            return
        if self._pump is None:
            self._pump = threading.Thread(target=self._sending, name="tree-link", daemon=True)
            self._pump.start()
        self._outbox.put(message)

    def _sending(self) -> None:
        while True:
            message = self._outbox.get()
            if message is None:
                return
            try:
                self.conn.send(message)
            except (OSError, EOFError, ValueError):
                self.gone = True
                return

    def flush(self, timeout: float) -> None:
        """Wait at most ``timeout`` seconds for every queued message to be sent, then end the
        sending thread."""
        if self._pump is not None:
            self._outbox.put(None)
            self._pump.join(timeout)

    def poll(self, tree: Any, current: float = math.inf) -> None:
        """Read every message waiting, hand out nodes if asked, share a better order and the
        rows this side separated since the last look (:data:`SHARE_ROWS`)."""
        self._share(tree)
        self._share_rows(tree)
        while not self.gone:
            try:
                if not self.conn.poll():
                    break
                message = self.conn.recv()
            except (OSError, EOFError):
                self.gone = True
                break
            self._read(tree, message)
        if self.main and self.gone and not self.closed and not self.lost:
            self._recover(tree)
        if self.wanted and not (self.gone or self.closing) and len(tree._open) >= 2:
            self._give(tree)
        if not self.main:
            report = (tree.bound(current) if tree._open else current, self.got)
            if report != self.reported:
                self.reported = report
                self.send(("bound", *report))

    def _read(self, tree: Any, message: tuple[Any, ...]) -> None:
        kind = message[0]
        if kind == "order":
            tree._new_order((float(message[1]), list(message[2])))
            self.shared = min(self.shared, float(message[1]))
        elif kind == "nodes":
            number, batch = message[1], message[2]
            for bound, depth, ones, zeros in batch:
                tree._push(bound, depth, ones, zeros, None, -1)
            self.taken += len(batch)
            self.got = max(self.got, number)
            self.asked = False
        elif kind == "rows":
            before = len(tree.model.cut_rows)
            rows, sides, weights = message[1], message[2], message[3]
            plain = [k for k, w in enumerate(weights) if w is None]
            if plain:
                tree._add_cuts([rows[k] for k in plain], [sides[k] for k in plain])
            if len(plain) < len(rows):
                tree._add_weighted(
                    [(rows[k], w, sides[k]) for k, w in enumerate(weights) if w is not None]
                )
            self.rows_taken += len(tree.model.cut_rows) - before
            self.rows_seen = len(tree.model.cut_rows)
        elif kind == "want":
            self.wanted = True
        elif kind == "bound":
            self._report(float(message[1]), int(message[2]))
        elif kind == "left":
            self._report(float(message[1]), int(message[2]))
            tree.peer_counts = dict(message[3])
            self.gone = self.closed = True
        elif kind == "stop":
            self.stopped = True

    def _report(self, bound: float, got: int) -> None:
        self.peer_bound = bound
        for number in [k for k in self.flight if k <= got]:
            del self.flight[number]

    def _recover(self, tree: Any) -> None:
        """The peer process ended without its last answer: every node ever sent to it comes
        back to this side's list (they cover the orders of every node it held: its nodes
        all descend from them, or were sent back and are here), and nothing is outside."""
        self.lost = True
        for bound, depth, ones, zeros in self.lent:
            tree._push(bound, depth, ones, zeros, None, -1)
        self.lent.clear()
        self.flight.clear()
        self.peer_bound = math.inf

    def _share_rows(self, tree: Any) -> None:
        model = tree.model
        count = len(model.cut_rows)
        if self.rows_seen < 0:  # the rows both sides started with
            self.rows_seen = count
        if not SHARE_ROWS or count <= self.rows_seen:
            self.rows_seen = count
            return
        new = range(self.rows_seen, count)
        rows = [model.cut_rows[k] for k in new]
        sides = [model.cut_sides[k] for k in new]
        weights = [model.cut_weights[k] for k in new]
        self.rows_seen = count
        self.send(("rows", rows, sides, weights))
        self.rows_sent += len(rows)

    def _share(self, tree: Any) -> None:
        known = tree.known
        if known is not None and known[0] < self.shared:
            self.shared = known[0]
            self.send(("order", known[0], list(known[1])))

    def _give(self, tree: Any) -> None:
        """Every other open node, best first, to the other side (this side keeps the best)."""
        nodes = sorted(tree._open)
        kept, given = nodes[0::2], nodes[1::2]
        tree._open = kept
        heapq.heapify(tree._open)
        self.sent += 1
        batch = [_wire(node) for node in given]
        if self.main:
            self.flight[self.sent] = min(node.bound for node in given)
            self.lent += batch
        self.send(("nodes", self.sent, batch))
        self.given += len(given)
        self.wanted = False

    # ------------------------------------------------------------------ states
    def outside(self) -> float:
        """Main side: the least bound of the nodes not in this process's list (the peer's
        report and the batches in flight; ``inf``: none)."""
        return min([self.peer_bound, *self.flight.values()])

    def idle(self, tree: Any, deadline: Deadline, margin: float) -> str:
        """This side's list is empty: ask for nodes and wait. Returns ``"nodes"`` (some
        came), ``"done"`` (main side: the tree is closed; peer side: told to stop) or
        ``"time_limit"``."""
        began = time.perf_counter()
        try:
            return self._idle(tree, deadline, margin)
        finally:
            self.waited += time.perf_counter() - began

    def _idle(self, tree: Any, deadline: Deadline, margin: float) -> str:
        if not self.asked:
            if not self.main and self.reported != (math.inf, self.got):
                self.reported = (math.inf, self.got)
                self.send(("bound", math.inf, self.got))
            self.send(("want",))
            self.asked = True
        while True:
            self.poll(tree)
            if tree._open:
                return "nodes"
            if self.main and (self.closed or (self.peer_bound == math.inf and not self.flight)):
                return "done"
            if not self.main and (self.stopped or self.gone):
                return "done"
            if deadline.expired(margin):
                return "time_limit"
            with contextlib.suppress(OSError, EOFError):
                self.conn.poll(IDLE_POLL)


class Peer:
    """The peer process (main side's handle): started at once, loaded later.

    Parameters
    ----------
    problem : SopProblem
    seconds : float or None
        Its own limit (it is stopped earlier by :meth:`close`).
    in_thread : bool
        Run the peer in a thread of this process instead (the protocol without a process's
        start-up: tests).
    """

    def __init__(self, problem: SopProblem, seconds: float | None, in_thread: bool = False) -> None:
        self.began = time.perf_counter()
        #: The wall-clock end (``time.time()``) of the peer's own limit: the same instant in
        #: both processes, whenever the peer starts.
        self.end = None if seconds is None else time.time() + seconds
        #: Cancels a thread peer's run (:meth:`close`); a process is killed instead.
        self.token = CancelToken()
        args = (problem, self.end, self.token if in_thread else None)
        self.process = PipedWorker(serve, args, "taopt-tree-peer", in_thread)
        self.conn = self.process.conn
        #: Whether the peer, once loaded, runs the root's stretch rows (its extended LP) before
        #: it takes nodes, and sends them here (the tree's root skipped them:
        #: :data:`taopt.models.sop_bc.SPLIT_STRETCH`); set by the tree.
        self.stretch = False
        self.ready = False
        self.link: Link | None = None
        #: Seconds from the start until this side saw it ready (None before; this side looks
        #: between two nodes of its tree).
        self.startup: float | None = None

    def poll_ready(self) -> bool:
        """Whether the peer has built its model (reads its ``ready`` message)."""
        if not self.ready and self.process.is_alive():
            with contextlib.suppress(OSError, EOFError):
                if self.conn.poll():
                    self.ready = self.conn.recv()[0] == "ready"
                    self.startup = time.perf_counter() - self.began
        return self.ready

    def load(self, tree: Any) -> Link | None:
        """Send the tree's model (rows, root fixings, best order) to a ready peer; its
        :class:`Link`, or None when it is not ready."""
        if self.link is not None or not self.poll_ready():
            return self.link
        model = tree.model
        weights = [None if w is None else np.asarray(w, float) for w in model.cut_weights]
        message = (
            "model",
            [np.asarray(r, np.int32) for r in model.cut_rows],
            [float(s) for s in model.cut_sides],
            weights,
            np.flatnonzero(model.fixed),
            bool(model.conditional),
            tree.known,
            bool(self.stretch),
        )
        try:
            self.conn.send(message)
        except (OSError, EOFError, ValueError):
            return None
        self.link = Link(self.conn, main=True)
        self.link.shared = math.inf if tree.known is None else tree.known[0]
        return self.link

    def close(self, tree: Any | None = None, closed: bool = False) -> None:
        """Stop the peer and reap it; with ``tree`` its last answer (orders, bound, counts)
        is read into it first.

        The wait for that answer is at most :data:`PEER_STOP_WAIT` (:data:`PEER_STOP_GRACE`
        where the tree is ``closed``: it needs nothing more of the peer, which answers at
        once unless it is inside its root), and ends :data:`PEER_STOP_GRACE` after the
        peer's own limit (it stops there by itself, as this side's tree does): the run's
        wall time stays within its allowance. Then the process is killed if it lingers; a
        thread's run is cancelled and joined."""
        link = self.link
        if link is not None:
            link.closing = True
        if link is not None and tree is not None and not link.gone:
            link.send(("stop",))
            wait = PEER_STOP_GRACE if closed else PEER_STOP_WAIT
            if self.end is not None:
                wait = min(wait, max(self.end + PEER_STOP_GRACE - time.time(), IDLE_POLL))
            until = time.perf_counter() + wait
            while not link.gone and time.perf_counter() < until:
                with contextlib.suppress(OSError, EOFError):
                    self.conn.poll(IDLE_POLL)
                link.poll(tree)
            self.process.join(PEER_STOP_GRACE)
        if link is not None:
            link.send(("stop",))
            link.flush(PEER_STOP_GRACE)
        else:
            with contextlib.suppress(OSError, EOFError, ValueError):
                self.conn.send(("stop",))  # a thread waiting for its model ends on it
        self.token.cancel()  # a thread's run stops at its next look (a process is killed)
        self.process.kill()
        self.process.join(None if self.process.thread is not None else PEER_STOP_GRACE)
        self.conn.close()


def serve(
    conn: Any, problem: SopProblem, end: float | None, token: CancelToken | None = None
) -> None:
    """The peer's work: build the model, take the rows, search the nodes it is given
    (:func:`search_given`), answer ``left``."""
    from taopt.models.sop_bc import BranchCut
    from taopt.models.sop_cuts import SopCutModel

    deadline = Deadline(None if end is None else max(end - time.time(), 0.0), cancel=token)
    model = SopCutModel(problem)
    try:
        conn.send(("ready",))
        message = conn.recv()
    except (OSError, EOFError):  # stopped before it was loaded
        return
    if message[0] != "model":
        return
    _, rows, sides, weights, fixed, conditional, known, stretch = message
    model.install(rows, sides, weights, fixed, conditional)
    tree = BranchCut(model, None if known is None else (float(known[0]), list(known[1])))
    link = Link(conn, main=False)
    link.shared = math.inf if known is None else float(known[0])
    link.rows_seen = len(model.cut_rows)  # the rows both sides start with
    tree.link = link
    began = time.perf_counter()
    stretched = 0.0
    try:
        if stretch:  # the root's stretch rows, sent to the other side at the first look
            model.root(deadline, stretch=True)
            stretched = time.perf_counter() - began
        search_given(tree, deadline)
    finally:
        bound = tree.bound() if tree._open else math.inf
        counts = {"nodes": tree.nodes, "lps": tree.lps, "cuts": tree.cuts, **link.counts()}
        counts["stretch_seconds"] = round(stretched, 3)
        counts["searched_seconds"] = round(time.perf_counter() - began - stretched, 3)
        link._share(tree)
        link.send(("left", bound, link.got, counts))
        link.flush(PEER_STOP_WAIT)  # sent before the process ends


def search_given(tree: Any, deadline: Deadline) -> None:
    """The peer's search: the nodes it is given until told to stop."""
    tree.run(deadline, root=False)
