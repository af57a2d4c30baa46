"""Lower bounds, each saying whether it is valid (DESIGN invariant 3).

Each bound is a ``functools.singledispatch`` function on the problem's class; families hook
their implementations in with :func:`taopt.registry.register_family`.

* :func:`arborescence` — valid. Chapter 2: Edmonds' min-cost arborescence with a super-root
  joined to every vehicle at zero cost. Chapter 3: the same per capability class. Chapter 5:
  Proposition 5.3's min-cost arborescence of G^d rooted at the depot. SOP: the arborescence
  rooted at the start node.
* :func:`thesis_mcga` — the thesis's Algorithm 1 ("MCGA") as printed (per class in chapter
  3, Theorem 3.4's f^a). Kept because Tables 2.1–2.2 and Figs. 3.4–3.6 are computed with it;
  NOT a valid lower bound on asymmetric matrices (it can exceed the optimum).
* :func:`doubled_arborescence` — Lemma 3.6's f^da, an upper bound on the optimum.
* :func:`mst` — Lemma 4.8's minimum-spanning-tree bound (chapter 4).
"""

from __future__ import annotations

import functools
from typing import Any

from taopt.errors import InstanceError


def _generic(name: str, doc: str) -> Any:
    def unknown(problem: Any) -> float:
        raise InstanceError(f"{name}() does not know problems of type {type(problem).__name__}")

    unknown.__name__ = name
    unknown.__qualname__ = name
    unknown.__doc__ = doc
    return functools.singledispatch(unknown)


arborescence = _generic(
    "arborescence", "Valid lower bound from a min-cost arborescence (Edmonds), per family."
)
thesis_mcga = _generic(
    "thesis_mcga",
    "The thesis's Algorithm 1 value f_a, as printed (not a valid bound on asymmetric costs).",
)
doubled_arborescence = _generic(
    "doubled_arborescence", "Lemma 3.6's f^da: every arborescence edge doubled (an upper bound)."
)
mst = _generic("mst", "Lemma 4.8's minimum-spanning-tree lower bound (chapter 4).")

__all__ = ["arborescence", "thesis_mcga", "doubled_arborescence", "mst"]
