"""The problem registry: one place that knows every problem family and its methods.

A *family* (chapter 2's :class:`~taopt.AssignmentProblem`, chapter 5's
:class:`~taopt.DeliveryInstance`, the SOP, ...) registers once, from its own core package,
with :func:`register_family`: its problem class, the ``kind`` of its JSON files, its payload
type, its one scorer and its bounds. The scorer and bounds are hooked into the
``functools.singledispatch`` functions :func:`taopt.evaluate` and ``taopt.bounds.*``, so
nothing else ever asks "which type of problem is this?".

A *method* (an exact model, a heuristic, a peer, a simulation policy) registers with the
:func:`register_method` decorator where it is defined (``taopt.models``,
``taopt.heuristics``); :func:`taopt.solve` looks it up by (problem class, name). A method is
a callable ``method(problem, **options) -> Solution``.

Adding a family changes no existing file: its spec is found by
:func:`taopt.families.ensure_families` and its methods by the packages ``taopt.models`` and
``taopt.heuristics``, which import every module they hold.

Example
-------
>>> import numpy as np, taopt
>>> from taopt.registry import family_of, method_names
>>> p = taopt.AssignmentProblem(np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]]), n_targets=2)
>>> family_of(p).kind
'assignment_problem'
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from taopt.errors import InstanceError

# ensure_families lives in taopt.families (which imports nothing of taopt, so taopt.result can
# use it without importing this module); re-exported here.
from taopt.families import ensure_families
from taopt.result import Solution

#: Method categories: how a method's result may be read.
CATEGORIES = ("exact", "heuristic", "peer", "simulation", "relaxation")


#: Sides of a bound: below the optimum (lower) or above it (upper).
SIDES = ("lower", "upper")


@dataclass(frozen=True)
class Bound:
    """A bound a family declares, and what it may be used for (docs/architecture.md, invariant 3).

    Attributes
    ----------
    func : callable
        ``func(problem) -> float``; for the name ``"lower"`` it is
        ``func(problem, strength) -> float`` (see :func:`taopt.bounds.lower`).
    valid : bool
        True when proven for every instance of the family; False for a value kept "as
        printed" by the thesis (e.g. Algorithm 1 on asymmetric costs), never quoted as a bound.
    side : {"lower", "upper"}
        A lower bound never exceeds the optimum; an upper bound is never below it.
    column : str
        The column of ``taopt solve``'s table holding f / this bound ("" for none; the table
        always has ``q_valid``, f over the family's fast valid lower bound).
    description : str
        One line (the function's docstring's first line by default).
    """

    func: Callable[..., float]
    valid: bool = True
    side: str = "lower"
    column: str = ""
    description: str = ""

    def __post_init__(self) -> None:
        if self.side not in SIDES:
            raise InstanceError(f"a bound's side is one of {SIDES}, got {self.side!r}")
        if not self.description:
            doc = (inspect.getdoc(self.func) or "").strip().splitlines()
            object.__setattr__(self, "description", doc[0] if doc else "")


@dataclass(frozen=True)
class Study:
    """A study command a family offers (``taopt study NAME``).

    Attributes
    ----------
    name : str
        The subcommand.
    module : str
        The orchestration module that runs it, imported only when the CLI is built: it
        defines ``add_arguments(parser)`` (its own options; the CLI adds ``--out``,
        ``--seed``, ``--time-limit``, ``--jobs``, ``--dask`` and ``--plot``), ``run(args) ->
        int`` and the constants ``HELP`` (one line) and ``CSV`` (its output file name).
        A string, so the core never imports the orchestration.
    """

    name: str
    module: str


@dataclass(frozen=True)
class Family:
    """A problem family's spec: everything generic code needs to know of it.

    Each family declares ONE such object in its own core package (``taopt/<pkg>/family.py``,
    found by :func:`taopt.families.ensure_families`) and registers it with
    :func:`register_family`. The CLI, ``taopt solve``/``verify``, the schema list, the
    study commands and the file-format tests are generated from these specs.

    Attributes
    ----------
    problem_type : type
        The problem class (instances of subclasses belong to it too).
    kind : str
        The ``kind`` of its JSON files (``"assignment_problem"``, ...); its JSON Schema is
        ``taopt/schemas/<kind>.schema.json`` and its example ``taopt/data/examples/<kind>.json``.
    payload : type
        The class of its solutions' payload (``Routes``, ``Plan``, ``Order``, ...).
    title : str
        A short human name ("open multi-vehicle routing, chapter 2").
    evaluate : callable
        ``evaluate(problem, payload) -> float``: the ONE scorer, which checks feasibility.
    load : callable
        ``load(dict) -> problem``: build a validated problem from JSON data
        (default ``problem_type.from_dict``).
    to_dict : callable
        ``to_dict(problem) -> dict`` (default ``problem.to_dict()``).
    bounds : dict
        ``name -> Bound``. The name ``"lower"`` is the family's strongest valid lower bound
        at a given cost (:func:`taopt.bounds.lower`); the others are reached by
        :func:`taopt.bounds.bound`.
    plots : dict
        ``name -> plot(problem, payload, path, instance=None, method="")`` writing a PNG
        (the first one is what ``taopt solve --plot`` draws; ``instance`` gives positions and
        the field when the problem came from an instance file, ``method`` is named in the
        title; a plot named ``gantt`` is what ``--gantt`` draws). Every family draws
        something for every file of its kind, so ``--plot`` never fails after the solve.
    adapter : callable, optional
        ``adapter(instance, progress) -> problem or None``: the family's problem built from an
        ``instance`` file (vehicles, targets, field), or None when the instance is not of
        this family (exactly one family accepts any instance).
    studies : tuple of Study
        Its ``taopt study`` commands.
    describe : callable, optional
        ``describe(problem, payload, instance=None) -> list of str``: the payload spelt with
        the ids drawn on the plot (``taopt solve --plot`` prints these lines under it; an
        ``instance`` gives the ids, else ``t0, t1, ...``). None: nothing is printed.
    exports : dict
        Public names reachable as ``taopt.<name>`` (the problem type at least).
    """

    problem_type: type[Any]
    kind: str
    payload: type
    title: str
    evaluate: Callable[[Any, Any], float]
    # None: the defaults below, set by __post_init__ (so never None once built)
    load: Callable[[Mapping[str, Any]], Any] = None  # type: ignore[assignment]
    to_dict: Callable[[Any], dict[str, Any]] = None  # type: ignore[assignment]
    bounds: Mapping[str, Bound] = field(default_factory=dict)
    plots: Mapping[str, Callable[..., Any]] = field(default_factory=dict)
    adapter: Callable[..., Any] | None = None
    studies: tuple[Study, ...] = ()
    describe: Callable[..., list[str]] | None = None
    exports: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.load is None:
            object.__setattr__(self, "load", self.problem_type.from_dict)
        if self.to_dict is None:
            object.__setattr__(self, "to_dict", lambda problem: problem.to_dict())
        bounds = {name: b if isinstance(b, Bound) else Bound(b) for name, b in self.bounds.items()}
        object.__setattr__(self, "bounds", bounds)
        exports = {self.problem_type.__name__: self.problem_type, **dict(self.exports)}
        object.__setattr__(self, "exports", exports)


@dataclass(frozen=True)
class Method:
    """A registered method of a family.

    Attributes
    ----------
    name : str
        As the user types it ("exact", "MC", "DAA", "pyvrp", ...).
    problem_type : type
    func : callable
        ``func(problem, **options) -> Solution``.
    category : str
        One of :data:`CATEGORIES`. Only "exact" methods may return status "optimal".
    warm_start : tuple of str
        Methods whose best payload :func:`taopt.solve` passes as ``incumbent=`` (the exact
        models take an incumbent, they never call heuristics themselves).
    description : str
        First line of the function's docstring.
    options : frozenset of str
        Keyword options the function names explicitly.
    takes_any : bool
        The function also takes arbitrary ``**options``.
    default : bool or callable
        Whether the method is in the default set of ``taopt solve`` (a callable gets the
        problem, e.g. an exact DP only for small instances).
    not_default : str or callable
        Why the method is not in the default set when ``default`` says no (a callable gets
        the problem): ``taopt solve`` prints it when no certified optimum is computed.
    requires : tuple of str
        Top-level packages the method needs (an optional extra such as ``pyvrp``); the
        method is :attr:`available` only when every one is installed.
    style : (linestyle, marker), optional
        How the method is drawn in every comparison plot, in black and white
        (:func:`taopt.plot.method_style`); the same name keeps one look in every family.
    certifies : bool or callable
        Whether this exact method is the family's *certifying method* for the problem: the
        fastest exact method, which ``taopt verify --exact`` re-solves with (a callable
        gets the problem, e.g. the DP over order ideals only while the ideals are affordable). See
        :func:`certifying_method`.
    """

    name: str
    problem_type: type
    func: Callable[..., Any]
    category: str = "heuristic"
    warm_start: tuple[str, ...] = ()
    description: str = ""
    options: frozenset[str] = frozenset()
    takes_any: bool = False
    default: bool | Callable[[Any], bool] = True
    not_default: str | Callable[[Any], str] = ""
    requires: tuple[str, ...] = ()
    certifies: bool | Callable[[Any], bool] = False
    style: tuple[str, str] | None = None

    def is_default_for(self, problem: Any) -> bool:
        """Whether ``taopt solve`` runs this method on ``problem`` when none are named."""
        return bool(self.default(problem) if callable(self.default) else self.default)

    def why_not_default(self, problem: Any) -> str:
        """Why ``taopt solve`` leaves this method out on ``problem`` ("" when it runs it)."""
        if self.is_default_for(problem):
            return ""
        reason = self.not_default(problem) if callable(self.not_default) else self.not_default
        return reason or f"{self.name} runs only when named (--methods {self.name})"

    @property
    def available(self) -> bool:
        """Whether every package in :attr:`requires` is installed (none is imported)."""
        return all(_installed(package) for package in self.requires)

    def certifies_for(self, problem: Any) -> bool:
        """Whether this is the certifying method of ``problem`` (see :func:`certifying_method`)."""
        if not self.exact:
            return False
        return bool(self.certifies(problem) if callable(self.certifies) else self.certifies)

    @property
    def exact(self) -> bool:
        return self.category == "exact"

    def accepts(self, option: str) -> bool:
        """Whether the method names keyword ``option`` (``seed``, ``time_limit``, ...)."""
        return option in self.options

    def check_options(self, options: Mapping[str, Any]) -> None:
        """Raise InstanceError naming an option this method does not take."""
        if self.takes_any:
            return
        unknown = sorted(set(options) - self.options)
        if unknown:
            raise InstanceError(
                f"method {self.name!r} does not take option(s) {unknown}; "
                f"it takes {sorted(self.options)}"
            )


@functools.cache
def _installed(package: str) -> bool:
    """Whether top-level ``package`` can be imported, found without importing it.

    ``importlib.util.find_spec`` only locates the package: importing ``ortools`` into a
    process that uses HiGHS would break cvxpy's HiGHS (docs/architecture.md, "Known traps").
    """
    return importlib.util.find_spec(package) is not None


_FAMILIES: dict[type, Family] = {}
_METHODS: dict[type, dict[str, Method]] = {}


def register_family(family: Family | type[Any], **spec: Any) -> Family:
    """Register a family's spec: its scorer, bounds, file kind, payload, plots and studies.

    Parameters
    ----------
    family : Family
        The spec (see :class:`Family`). For brevity a problem class with the spec's fields as
        keywords is accepted too: ``register_family(P, kind=..., payload=..., ...)``.

    Returns
    -------
    Family
        The registered spec.

    Raises
    ------
    InstanceError
        Another family already has this file kind.
    """
    from taopt.scoring import evaluate as generic_evaluate

    if not isinstance(family, Family):
        family = Family(problem_type=family, **spec)
    elif spec:
        raise InstanceError("register_family takes a Family or a problem type with keywords")
    for other in _FAMILIES.values():
        if other.kind == family.kind and other.problem_type is not family.problem_type:
            raise InstanceError(f"file kind {family.kind!r} is already registered")
    _FAMILIES[family.problem_type] = family
    _METHODS.setdefault(family.problem_type, {})
    generic_evaluate.register(family.problem_type, _scorer(family.evaluate, family.payload))
    return family


def _scorer(evaluate: Callable[[Any, Any], float], payload: type) -> Callable[[Any, Any], float]:
    def score(problem: Any, solution: Any) -> float:
        if isinstance(solution, Solution):
            solution = solution.solution
            if solution is None:
                raise InstanceError("this solution carries no payload to evaluate")
        return float(evaluate(problem, solution))

    score.__doc__ = evaluate.__doc__
    return score


def register_method(
    problem_type: type,
    name: str,
    *,
    category: str = "heuristic",
    warm_start: tuple[str, ...] | str = (),
    default: bool | Callable[[Any], bool] = True,
    not_default: str | Callable[[Any], str] = "",
    requires: tuple[str, ...] | str = (),
    certifies: bool | Callable[[Any], bool] = False,
    style: tuple[str, str] | None = None,
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorator: register ``func(problem, **options) -> Solution`` as method ``name``.

    Parameters
    ----------
    problem_type : type
        The family's problem class.
    name : str
        As the user types it.
    category : str
        One of :data:`CATEGORIES`.
    warm_start : str or tuple of str
        Methods whose best payload :func:`taopt.solve` passes as ``incumbent=``.
    default : bool or callable
        Whether ``taopt solve`` runs it when no method is named (a callable gets the problem).
    not_default : str or callable
        The one line ``taopt solve`` prints when an exact method is left out.
    requires : str or tuple of str
        Top-level packages it needs (optional extras); see :attr:`Method.available`.
    certifies : bool or callable
        Exact methods only: marks the family's fastest exact method where it applies
        (``taopt verify --exact`` re-solves with it); see :func:`certifying_method`.
    style : (linestyle, marker), optional
        Its look in comparison plots (:func:`taopt.plot.method_style`).

    Example
    -------
    >>> @register_method(AssignmentProblem, "MC")          # doctest: +SKIP
    ... def mc(problem, seed=0): ...
    """
    if category not in CATEGORIES:
        raise InstanceError(f"unknown method category {category!r}; one of {CATEGORIES}")

    def wrap(func: Callable[..., Any]) -> Callable[..., Any]:
        signature = inspect.signature(func)
        params = list(signature.parameters.values())[1:]
        takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params)
        options = frozenset(
            p.name
            for p in params
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        )
        doc = (inspect.getdoc(func) or "").strip().splitlines()
        _METHODS.setdefault(problem_type, {})[name] = Method(
            name=name,
            problem_type=problem_type,
            func=func,
            category=category,
            warm_start=(warm_start,) if isinstance(warm_start, str) else tuple(warm_start),
            description=doc[0] if doc else "",
            options=options,
            takes_any=takes_any,
            default=default,
            not_default=not_default,
            requires=(requires,) if isinstance(requires, str) else tuple(requires),
            certifies=certifies,
            style=style,
        )
        return func

    return wrap


_IMPROVERS: dict[type, Callable[..., Any]] = {}


def register_improver(problem_type: type) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Decorator: ``func`` improves the incumbents inside the exact model of ``problem_type``.

    An exact model that takes an ``improve`` argument calls it on the feasible answers its
    own rounds produce (its docstring gives the signature); :func:`taopt.solve` passes the
    registered one. Heuristic modules register theirs where they are defined, so an exact
    model never imports a heuristic (an incumbent and an improver are passed in). The last
    registration for a type wins.
    """

    def wrap(func: Callable[..., Any]) -> Callable[..., Any]:
        _IMPROVERS[problem_type] = func
        return func

    return wrap


def improver(problem: Any) -> Callable[..., Any] | None:
    """The improver registered for the family of ``problem`` (imported modules only), or None."""
    return _IMPROVERS.get(family_of(problem).problem_type)


def method_style(name: str) -> tuple[str, str] | None:
    """The (linestyle, marker) some registration of method ``name`` declares (None if none)."""
    for found in _METHODS.values():
        method = found.get(name)
        if method is not None and method.style is not None:
            return method.style
    return None


def family_of(item: Any) -> Family:
    """The family of a problem, or of a problem class (or a registered base class of it)."""
    cls = item if isinstance(item, type) else type(item)
    for base in cls.__mro__:
        if base in _FAMILIES:
            return _FAMILIES[base]
    raise InstanceError(
        f"{cls.__name__} is not a registered problem type; "
        f"known: {sorted(c.__name__ for c in _FAMILIES)}"
    )


def family_for_kind(kind: Any) -> Family:
    """The family whose files have ``"kind": kind``."""
    ensure_families()
    for family in _FAMILIES.values():
        if family.kind == kind:
            return family
    raise InstanceError(f"unknown file kind {kind!r}; known: {sorted(file_kinds())}")


def file_kinds() -> list[str]:
    """Every registered file kind."""
    ensure_families()
    return [f.kind for f in _FAMILIES.values()]


def families() -> list[Family]:
    """Every registered family."""
    ensure_families()
    return list(_FAMILIES.values())


def methods(problem: Any, category: str | None = None) -> dict[str, Method]:
    """Registered methods for ``problem`` (or its class), optionally of one category.

    Methods register where they are defined, in ``taopt.models`` (every exact method) and
    ``taopt.heuristics`` (heuristics, peers, simulation policies); the core never imports
    those packages, so this lists what has been imported. The orchestration imports both
    (:mod:`taopt.orchestration.pipeline`), so :func:`taopt.available_methods` and :func:`taopt.solve`
    always see every method. Peers whose package is missing are listed here but not by
    :func:`taopt.available_methods`.
    """
    family = family_of(problem)
    found = dict(_METHODS.get(family.problem_type, {}))
    if category is not None:
        found = {k: v for k, v in found.items() if v.category == category}
    return found


def certifying_method(problem: Any) -> str | None:
    """The exact method that certifies ``problem`` fastest (``taopt verify --exact`` uses it).

    The first exact method registered with ``certifies`` true for the problem (e.g. the
    DP over order ideals of a delivery instance with at most 2,000,000 ideals); else the family's
    method "exact"; else its first exact method; None when it has none. Only methods
    whose modules are imported count (see :func:`methods`): the core imports no method, so
    callers use :func:`taopt.orchestration.pipeline.certifying_method`, which has imported
    every one (the same answer whatever was imported before).
    """
    exact = methods(problem, "exact")
    for name, spec in exact.items():
        if spec.certifies_for(problem):
            return name
    if "exact" in exact:
        return "exact"
    return next(iter(exact), None)


def method_names(problem: Any, category: str | None = None) -> list[str]:
    """Names of :func:`methods`, in registration order."""
    return list(methods(problem, category))


def get_method(problem: Any, name: str) -> Method:
    """The method ``name`` for ``problem``, or InstanceError listing what exists.

    Names are matched case-insensitively (``"mc"`` is ``"MC"``, ``"Exact"`` is ``"exact"``);
    the returned spec's ``name`` is the registered spelling.
    """
    found = methods(problem)
    if name in found:
        return found[name]
    folded = {key.casefold(): spec for key, spec in found.items()}
    if isinstance(name, str) and name.strip().casefold() in folded:
        return folded[name.strip().casefold()]
    family = family_of(problem)
    raise InstanceError(
        f"no method {name!r} for {family.problem_type.__name__}; choose from {sorted(found)}"
    )


__all__ = [
    "CATEGORIES",
    "SIDES",
    "Bound",
    "Study",
    "Family",
    "Method",
    "register_family",
    "register_method",
    "register_improver",
    "improver",
    "ensure_families",
    "family_of",
    "family_for_kind",
    "file_kinds",
    "families",
    "methods",
    "method_names",
    "certifying_method",
    "method_style",
    "get_method",
]
