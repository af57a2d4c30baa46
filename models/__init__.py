"""Exact formulations (cvxpy + HiGHS), as ``taopt.models``.

* :func:`solve_routing` — chapter 2, (2.2)–(2.5) with DFJ / MTZ / flow subtour elimination.
* :func:`solve_delivery` — chapter 5, a linear equivalent of (5.1)–(5.7).
* :func:`solve_sop` — sequential ordering (precedence-constrained Hamiltonian path).
"""

from taopt.models.delivery import solve_delivery
from taopt.models.routing import solve_routing
from taopt.models.sop import solve_sop

__all__ = ["solve_routing", "solve_delivery", "solve_sop"]
