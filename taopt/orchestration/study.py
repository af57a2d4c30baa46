"""The one study runner: scenarios × registered methods → a resumable CSV, on any executor.

A study is described by a :class:`StudySpec`: which columns identify a scenario (its *key*),
a module-level ``make_scenario(key, settings) -> Scenario`` that builds the problem (and its
per-scenario data and reference values, e.g. a bound) deterministically from the key and the
settings, and which ``Solution.info`` entries to keep. :func:`run_study` runs every
(scenario, method) pair that the output folder does not hold yet, through
:func:`taopt.solve`, and appends one row per pair to ``<out>/<name>.csv`` through
:class:`taopt.orchestration.studyio.ResultsStore` (settings checked, torn lines dropped, resumable).

Execution
---------
* Tasks (one scenario with its missing methods) run in worker processes — a process pool of
  ``jobs`` workers (``jobs=1`` too, so that Ctrl-C is never swallowed by a solver's own
  signal handler), or a Dask cluster through ``Client.get_executor()`` (``dask="local"`` for
  a ``LocalCluster`` of ``jobs`` single-threaded workers, or a scheduler address), or any
  ``concurrent.futures.Executor`` given as ``executor``.
* Only this (the client) process writes rows, so resuming stays trivial.
* Solver threads are 1 inside tasks (``OMP_NUM_THREADS`` & co., and HiGHS's ``threads``
  through ``TAOPT_SOLVER_THREADS``).
* Every argument is validated before anything is written: an invalid call leaves the output
  folder as it was. Method options with a known meaning (``generations``, ``population``,
  rates, ...) are checked here too (:data:`OPTION_RULES`), and a Dask scheduler address is
  probed with a short connect timeout (:data:`DASK_CONNECT_TIMEOUT`) before the folder is made.
* One writer per folder: the run holds :func:`taopt.orchestration.studyio.folder_lock` (an OS-level lock)
  while it writes; a second run on the same folder is refused at once
  (:class:`~taopt.orchestration.studyio.StudyLocked`, naming the holder's pid). A folder whose rows are all
  finished is only read: no lock, nothing written (a read-only folder can be reported on).
* Ctrl-C (SIGINT) or SIGTERM stops the study at once: pending tasks are cancelled, worker processes are
  killed (pool workers also die with their parent if it is killed:
  :class:`taopt.runtime.workers.WorkerPool`), finished rows stay on disk, and :class:`StudyInterrupted`
  is raised; running the same call again resumes.

Rows: the key columns, the scenario columns, ``method, objective, status, bound, runtime,
seed``, the reference columns and the info columns. The same (key, settings) give the same
rows (timing aside) whatever the executor.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import signal
import zlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, Future, as_completed
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np
import pandas as pd

import taopt.heuristics  # noqa: F401  (registers the heuristics: get_method below)
import taopt.models  # noqa: F401  (registers the exact models)
from taopt.errors import InstanceError, TaoptError
from taopt.orchestration.pipeline import solve
from taopt.orchestration.studyio import ResultsStore, StudyLocked, folder_lock, normalize_key
from taopt.registry import get_method
from taopt.runtime.interrupt import handled, raise_interrupt
from taopt.runtime.workers import (
    ONE_THREAD_ENV,
    WorkerPool,
    become_worker,
    drop_pool,
    kill_processes,
    shared_pool,
)

logger = logging.getLogger("taopt")

RESULT_COLUMNS = ("method", "objective", "status", "bound", "runtime", "seed")
#: Environment for worker processes: one solver / BLAS thread per task.
THREAD_ENV = ONE_THREAD_ENV

#: Method options a study checks before anything is written (the methods check them again):
#: option name -> ("integer", smallest) or ("rate",) for a number in [0, 1].
OPTION_RULES: dict[str, tuple[Any, ...]] = {
    "generations": ("integer", 0),
    "population": ("integer", 2),
    "tournament": ("integer", 1),
    "crossover_rate": ("rate",),
    "mutation_rate": ("rate",),
    "crossover": ("rate",),
    "mutation": ("rate",),
}
#: Seconds to wait for a Dask scheduler to accept a connection before the study is refused.
DASK_CONNECT_TIMEOUT = 5.0

__all__ = [
    "Scenario",
    "StudySpec",
    "StudyInterrupted",
    "StudyLocked",
    "run_study",
    "with_optimum",
    "check_integer",
    "check_positive",
    "parse_integers",
    "RESULT_COLUMNS",
    "OPTION_RULES",
]


class StudyInterrupted(TaoptError, KeyboardInterrupt):
    """A study stopped by Ctrl-C; the rows finished so far are on disk."""


@dataclass(frozen=True)
class Scenario:
    """One scenario of a study: the problem, its data columns and its reference values."""

    problem: Any
    columns: Mapping[str, Any] = field(default_factory=dict)
    references: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class StudySpec:
    """What a study is: its key, its scenario factory and the columns it keeps.

    Attributes
    ----------
    name : str
        The CSV is ``<out>/<name>.csv``, its settings ``<out>/<name>.config.json``.
    problem_type : type
        The registered problem class the scenarios build (methods are checked against it
        before anything runs).
    key_columns : tuple of str
        The columns that identify a scenario (the method is added to make a row's key).
    make_scenario : callable
        Module-level ``make_scenario(key: dict, settings: dict) -> Scenario``; deterministic.
        ``settings["context"]`` holds run-time context that does not change the numbers
        (e.g. a cache folder) and is not saved.
    scenario_columns, reference_columns, info_columns : tuple of str
        Columns taken from ``Scenario.columns``, ``Scenario.references`` and each
        ``Solution.info`` (NaN when absent).
    method_seed : callable, optional
        Module-level ``method_seed(key, settings) -> int``; default: a hash of the key and the
        settings' ``seed``.
    """

    name: str
    problem_type: type
    key_columns: tuple[str, ...]
    make_scenario: Callable[[dict, dict], Scenario]
    scenario_columns: tuple[str, ...] = ()
    reference_columns: tuple[str, ...] = ()
    info_columns: tuple[str, ...] = ()
    method_seed: Callable[[dict, dict], int] | None = None

    @property
    def columns(self) -> list[str]:
        return [
            *self.key_columns,
            *self.scenario_columns,
            *RESULT_COLUMNS,
            *self.reference_columns,
            *self.info_columns,
        ]

    @property
    def row_key(self) -> list[str]:
        return [*self.key_columns, "method"]


def _default_seed(key: Mapping[str, Any], settings: Mapping[str, Any]) -> int:
    text = json.dumps({"key": dict(key), "seed": settings.get("seed", 0)}, sort_keys=True)
    return zlib.crc32(text.encode())


# -- the task (runs in a worker) ---------------------------------------------------------------


def _configure_worker() -> None:
    """One thread per solver; ignore Ctrl-C (the client handles it). A pool's workers also
    die with the parent (:class:`taopt.runtime.workers.WorkerPool`)."""
    become_worker(env=THREAD_ENV)


def run_task(
    spec: StudySpec,
    key: Mapping[str, Any],
    methods: Sequence[str],
    settings: Mapping[str, Any],
    time_limit: float | None,
    method_options: Mapping[str, Mapping[str, Any]],
) -> list[dict[str, Any]]:
    """Build scenario ``key`` and run ``methods`` on it; return its rows (one per method)."""
    os.environ.update(THREAD_ENV)
    key, settings = dict(key), dict(settings)
    scenario = spec.make_scenario(key, settings)
    seed = (spec.method_seed or _default_seed)(key, settings)
    rows = []
    for name in methods:
        solution = solve(
            scenario.problem,
            name,
            seed=seed,
            time_limit=time_limit,
            **dict(method_options.get(name, {})),
        )
        row: dict[str, Any] = {c: key[c] for c in spec.key_columns}
        row.update({c: scenario.columns.get(c, math.nan) for c in spec.scenario_columns})
        row.update(
            method=name,
            objective=solution.objective,
            status=solution.status.value,
            bound=math.nan if solution.bound is None else solution.bound,
            runtime=solution.runtime,
            seed=solution.seed if solution.seed is not None else seed,
        )
        row.update({c: scenario.references.get(c, math.nan) for c in spec.reference_columns})
        row.update({c: _scalar(solution.info.get(c)) for c in spec.info_columns})
        rows.append(row)
    return rows


def _scalar(value: Any) -> Any:
    if value is None:
        return math.nan
    if isinstance(value, (bool, int, float, str, np.integer, np.floating)):
        return value
    return json.dumps(value)


# -- argument checks (every study calls them before anything is written) -------------------------


def check_integer(label: str, value: Any, low: int = 0) -> int:
    """``value`` as an int, or :class:`InstanceError` naming ``label`` unless it is an integer
    ``>= low`` (a float such as 3.0 is accepted as 3; ``True`` is not a count)."""
    whole = isinstance(value, (float, np.floating)) and math.isfinite(value) and value == int(value)
    if isinstance(value, (bool, np.bool_)) or not (isinstance(value, (int, np.integer)) or whole):
        raise InstanceError(f"{label} must be an integer >= {low}, got {_show(value)}")
    if int(value) < low:
        raise InstanceError(f"{label} must be an integer >= {low}, got {int(value)}")
    return int(value)


@overload
def check_positive(label: str, value: Any, allow_none: Literal[False] = False) -> float: ...


@overload
def check_positive(label: str, value: Any, allow_none: bool) -> float | None: ...


def check_positive(label: str, value: Any, allow_none: bool = False) -> float | None:
    """``value`` as a float, or :class:`InstanceError` naming ``label`` unless it is a finite
    number > 0 (``None`` passes when ``allow_none``)."""
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise InstanceError(f"{label} must be a positive number, got {_show(value)}")
    if not (math.isfinite(float(value)) and float(value) > 0):
        raise InstanceError(f"{label} must be a positive finite number, got {float(value):g}")
    return float(value)


def parse_integers(label: str, values: Any, low: int = 0) -> list[int]:
    """A comma-separated string (``"1,3,5"``) or a sequence of integers, each ``>= low``;
    :class:`InstanceError` naming ``label`` and the offending item otherwise."""
    if isinstance(values, str):
        items: list[Any] = [part.strip() for part in values.split(",") if part.strip()]
    else:
        items = list(values)
    if not items:
        raise InstanceError(f"{label}: no values given")
    out = []
    for item in items:
        if isinstance(item, str):
            try:
                item = int(item)
            except ValueError:
                raise InstanceError(
                    f"{label}: {item!r} is not an integer (expected e.g. 1,3,5)"
                ) from None
        out.append(check_integer(label, item, low))
    return out


def _show(value: Any) -> str:
    """A value for a message: numbers plain (``20`` or ``0.5``, never ``np.float64(20.0)``)."""
    if isinstance(value, (np.integer, np.floating)):
        value = value.item()
    return f"{value:g}" if isinstance(value, float) else repr(value)


def _check_option_values(name: str, options: Mapping[str, Any]) -> None:
    for option, value in options.items():
        rule = OPTION_RULES.get(option)
        if rule is None:
            continue
        label = f"method {name!r} option {option!r}"
        if rule[0] == "integer":
            check_integer(label, value, rule[1])
        elif isinstance(value, (bool, np.bool_)) or not (
            isinstance(value, (int, float, np.number)) and 0.0 <= float(value) <= 1.0
        ):
            raise InstanceError(f"{label} must be a number in [0, 1], got {_show(value)}")


def check_dask_address(address: str, timeout: float = DASK_CONNECT_TIMEOUT) -> None:
    """Refuse a Dask scheduler address that does not accept a TCP connection in ``timeout``
    seconds (``tcp://host:port``, ``tls://host:port`` or ``host:port``; other transports are
    left to Dask). Called before the study folder is created.

    Raises
    ------
    InstanceError
        The address is malformed or nothing answers there.
    """
    import socket
    from urllib.parse import urlsplit

    if not isinstance(address, str) or not address.strip():
        raise InstanceError(f"dask must be 'local' or a scheduler address, got {address!r}")
    text = address.strip()
    parts = urlsplit(text if "://" in text else f"tcp://{text}")
    if parts.scheme not in ("tcp", "tls"):
        return
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or port is None:
        raise InstanceError(f"dask address {address!r} is not tcp://host:port")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
        raise InstanceError(
            f"no Dask scheduler at {address} ({reason} within {timeout:g} s); nothing written"
        ) from None


# -- the runner ---------------------------------------------------------------------------------


def _check_arguments(
    spec: StudySpec,
    keys: Sequence[Mapping[str, Any]],
    methods: Sequence[str],
    jobs: int,
    time_limit: float | None,
    method_options: Mapping[str, Mapping[str, Any]],
) -> None:
    if not keys:
        raise InstanceError("the study has no scenarios (need at least 1)")
    for key in keys:
        missing = [c for c in spec.key_columns if c not in key]
        if missing:
            raise InstanceError(f"scenario key {dict(key)} lacks {missing}")
    if not methods:
        raise InstanceError("no methods given")
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise InstanceError(f"jobs must be an integer >= 1, got {jobs!r}")
    if time_limit is not None and not (
        isinstance(time_limit, (int, float)) and math.isfinite(time_limit) and time_limit > 0
    ):
        raise InstanceError(f"time_limit must be a positive number of seconds, got {time_limit!r}")
    for name in dict.fromkeys([*methods, *method_options]):
        method = get_method(spec.problem_type, name)
        if not method.available:
            raise InstanceError(
                f"method {method.name!r} needs {', '.join(method.requires)}, not installed here "
                "(pip install 'taopt[peers]'); leave it out of --methods; nothing written"
            )
        method.check_options(dict(method_options.get(name, {})))
        _check_option_values(name, dict(method_options.get(name, {})))


def _canonical(problem_type: Any, name: str) -> str:
    """The registered spelling of method ``name`` (case-insensitive), or ``name`` unchanged
    when it is unknown (the argument check names it)."""
    try:
        return get_method(problem_type, name).name
    except TaoptError:
        return name


def canonical_methods(problem_type: Any, methods: str | Sequence[str]) -> list[str]:
    """Method names (a comma string or a list) in their registered spelling, deduplicated:
    ``"mc,ga"`` -> ``["MC", "GA"]``; an unknown name is an InstanceError listing the
    family's methods (raised before anything is written)."""
    if isinstance(methods, str):
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    return list(dict.fromkeys(get_method(problem_type, m).name for m in methods))


def available_defaults(problem_type: Any, names: Sequence[str]) -> list[str]:
    """The methods of ``names`` installed here (a study's default methods: a peer whose
    package is missing is left out, not run to fail)."""
    return [name for name in names if get_method(problem_type, name).available]


def _pool(jobs: int) -> WorkerPool:
    """A spawned pool of ``jobs`` workers, kept for the next study of this process."""
    return shared_pool(("study", jobs), jobs, env=THREAD_ENV)


def _executor(
    jobs: int, dask: str | None
) -> tuple[Executor, Callable[[], None], Callable[[], None]]:
    """(executor, close, kill) for a process pool or a Dask cluster."""
    if dask is None:
        pool = _pool(int(jobs))
        return pool, lambda: None, lambda: drop_pool(("study", int(jobs)))
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InstanceError('Dask is not installed: pip install "taopt[dask]"') from None
    if dask == "local":
        cluster = LocalCluster(
            n_workers=int(jobs),
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=50,
        )
        client = Client(cluster)
    else:
        cluster = None
        client = Client(dask)
    client.run(_configure_worker)

    def close() -> None:
        with contextlib.suppress(Exception):
            client.close(timeout=5)
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close(timeout=5)

    # a local cluster's processes are ours: on Ctrl-C they are killed outright (a graceful
    # close would cancel the task threads mid-solve and let native code complain on stderr)
    local = []
    if cluster is not None:
        pids = {*client.run(os.getpid).values(), *client.run(os.getpid, nanny=True).values()}
        local = sorted(pids - {os.getpid()})  # a LocalCluster's nannies live in this process

    def kill_cluster() -> None:
        if cluster is not None:
            for nanny in list(getattr(cluster, "workers", {}).values()):
                with contextlib.suppress(Exception):
                    nanny.close_gracefully()  # do not restart the worker it is about to lose
        kill_processes(local)
        if cluster is not None:
            # its workers are gone: Dask's exit hook would otherwise wait 10 s to close it
            cluster.shutdown_on_close = False
        with contextlib.suppress(Exception):
            client.close(timeout=1)

    return client.get_executor(), close, kill_cluster


@contextlib.contextmanager
def _thread_environment() -> Iterator[None]:
    """Set :data:`THREAD_ENV` while workers are started (they inherit it), then restore."""
    saved = {k: os.environ.get(k) for k in THREAD_ENV}
    os.environ.update(THREAD_ENV)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def run_study(
    spec: StudySpec,
    keys: Sequence[Mapping[str, Any]],
    methods: Sequence[str],
    settings: Mapping[str, Any],
    out_dir: str | os.PathLike[str],
    *,
    jobs: int = 1,
    dask: str | None = None,
    executor: Executor | None = None,
    time_limit: float | None = None,
    method_options: Mapping[str, Mapping[str, Any]] | None = None,
    context: Mapping[str, Any] | None = None,
    progress: bool = True,
) -> pd.DataFrame:
    """Run every missing (scenario, method) pair of a study and return its rows.

    Parameters
    ----------
    spec : StudySpec
    keys : sequence of dict
        One dict per scenario, holding every key column.
    methods : sequence of str
        Registered methods of ``spec.problem_type`` (checked before anything runs).
    settings : dict
        JSON data that changes the numbers (sizes, seed, field, ...); saved next to the rows
        and compared on resume. ``time_limit`` and ``method_options`` are added to it.
    out_dir : path
        Folder of ``<name>.csv`` and ``<name>.config.json``.
    jobs : int
        Worker processes (a process pool) or Dask workers (``dask="local"``).
    dask : str, optional
        ``"local"`` for a LocalCluster, or a scheduler address (``tcp://host:8786``).
    executor : concurrent.futures.Executor, optional
        Any executor instead (its tasks must be able to import taopt); not shut down here.
    time_limit : float, optional
        Seconds per method run (exact models and peers take it).
    method_options : dict, optional
        ``{method: {option: value}}``.
    context : dict, optional
        Run-time context handed to ``make_scenario`` as ``settings["context"]`` (not saved,
        not compared: e.g. a cache folder).
    progress : bool
        A tqdm bar over scenarios.

    Returns
    -------
    pandas.DataFrame
        The rows of the requested keys and methods on disk (earlier runs included), sorted by
        key, methods in the requested order.

    Raises
    ------
    InstanceError
        A bad argument (nothing is written; a Dask address that does not answer included),
        or the folder holds rows of other settings.
    StudyLocked
        Another study is writing to ``out_dir`` (raised at once, nothing written).
    StudyInterrupted
        Ctrl-C; the finished rows are on disk and a re-run resumes.
    """
    keys = [dict(k) for k in keys]
    # registered spellings ("mc" -> "MC"); an unknown name is refused below, before writing
    methods = list(dict.fromkeys(_canonical(spec.problem_type, m) for m in methods))
    method_options = {
        _canonical(spec.problem_type, k): v for k, v in (method_options or {}).items()
    }
    options = {k: dict(v) for k, v in (method_options or {}).items()}
    _check_arguments(spec, keys, methods, jobs, time_limit, options)
    if dask is not None and executor is not None:
        raise InstanceError("give either dask or executor, not both")
    if dask is not None and dask != "local":
        check_dask_address(dask)
    saved = {
        **dict(settings),
        "time_limit": None if time_limit is None else float(time_limit),
        "method_options": options,
    }

    def open_store(write: bool) -> tuple[ResultsStore, list[tuple[Mapping[str, Any], list[str]]]]:
        store = ResultsStore(
            out_dir,
            f"{spec.name}.csv",
            spec.columns,
            spec.row_key,
            saved,
            config=f"{spec.name}.config.json",
            write=write,
        )
        done = store.done_keys()
        tasks = []
        for key in keys:
            base = [key[c] for c in spec.key_columns]
            missing = [m for m in methods if normalize_key([*base, m]) not in done]
            if missing:
                tasks.append((key, missing))
        return store, tasks

    store, tasks = open_store(write=False)  # reading needs no lock and writes nothing
    if not tasks:
        return _table(store.read(), spec, keys, methods)
    with folder_lock(out_dir):
        store, tasks = open_store(write=True)  # again under the lock: rows may have landed
        _run_tasks(
            spec,
            store,
            keys,
            tasks,
            saved,
            jobs,
            dask,
            executor,
            time_limit,
            options,
            context,
            progress,
        )
    return _table(store.read(), spec, keys, methods)


def _run_tasks(
    spec: StudySpec,
    store: ResultsStore,
    keys: Sequence[Mapping[str, Any]],
    tasks: Sequence[tuple[Mapping[str, Any], list[str]]],
    saved: Mapping[str, Any],
    jobs: int,
    dask: str | None,
    executor: Executor | None,
    time_limit: float | None,
    options: Mapping[str, Mapping[str, Any]],
    context: Mapping[str, Any] | None,
    progress: bool,
) -> None:
    """Run ``tasks`` on the executor and append each scenario's rows as it finishes."""
    worker_settings = {**saved, "context": dict(context or {})}

    from tqdm.auto import tqdm

    bar = tqdm(
        total=len(keys),
        initial=len(keys) - len(tasks),
        disable=not progress,
        desc=spec.name,
        unit="scenario",
    )
    close = kill = None
    signals = contextlib.ExitStack()  # SIGTERM (a job scheduler's stop) ends it as Ctrl-C does
    signals.enter_context(handled(signal.SIGTERM, raise_interrupt))
    try:
        if tasks:
            if executor is None:
                with _thread_environment():
                    executor, close, kill = _executor(jobs, dask)
            futures: list[Future] = [
                executor.submit(run_task, spec, key, todo, worker_settings, time_limit, options)
                for key, todo in tasks
            ]
            named = {m for _, todo in tasks for m in todo}
            exact = {m for m in named if get_method(spec.problem_type, m).exact}
            for future in as_completed(futures):
                rows = future.result()
                store.append(rows)  # one scenario's rows in one write
                _flag_uncertified(spec, rows, exact, time_limit)
                bar.update(1)
    except KeyboardInterrupt:
        bar.close()
        if kill is not None:
            kill()
        rows = len(store.done_keys())
        raise StudyInterrupted(
            f"interrupted: {rows} rows are saved in {store.path}; run the same command again "
            "to resume"
        ) from None
    else:
        bar.close()
        if close is not None:
            close()
    finally:
        signals.close()


def _flag_uncertified(
    spec: StudySpec, rows: Sequence[Mapping[str, Any]], exact: set[str], time_limit: Any
) -> None:
    """Warn (logger ``taopt``) about an exact row that is neither optimal nor infeasible
    although no time limit stopped it: docs/architecture.md, invariant 4 says that is a bug."""
    if time_limit is not None:
        return
    for row in rows:
        if row["method"] in exact and row["status"] not in ("optimal", "infeasible"):
            key = ", ".join(f"{c}={row[c]}" for c in spec.key_columns)
            logger.warning(
                "%s: exact method %r ended %r without a time limit (scenario %s): not certified",
                spec.name,
                row["method"],
                row["status"],
                key,
            )


def _table(
    df: pd.DataFrame, spec: StudySpec, keys: Sequence[Mapping[str, Any]], methods: Sequence[str]
) -> pd.DataFrame:
    wanted = {normalize_key([k[c] for c in spec.key_columns]) for k in keys}
    key_values = zip(*(df[c] for c in spec.key_columns), strict=True)
    mask = np.array([normalize_key(v) in wanted for v in key_values], dtype=bool)
    df = df.loc[mask] if len(df) else df
    df = df[df["method"].isin(methods)]
    order = {name: i for i, name in enumerate(methods)}
    df = df.assign(_order=df["method"].map(order)).sort_values([*spec.key_columns, "_order"])
    return df.drop(columns=["_order"]).reset_index(drop=True)


def with_optimum(
    df: pd.DataFrame, spec: StudySpec, exact: Sequence[str] = ("exact",)
) -> pd.DataFrame:
    """Add per-scenario ``optimum`` (a proven optimum from an exact row) and ``exact_bound``.

    A scenario's ``optimum`` is the objective of one of its ``exact`` rows whose status is
    "optimal" (NaN otherwise; an existing ``optimum`` reference column is kept where set);
    ``exact_bound`` is the largest proven bound of its exact rows.
    """
    df = df.copy()
    keys = list(spec.key_columns)
    rows = df[df["method"].isin(exact)]
    proven = rows[rows["status"] == "optimal"].groupby(keys)["objective"].min()
    bound = rows.groupby(keys)["bound"].max()
    index = pd.MultiIndex.from_frame(df[keys]) if len(keys) > 1 else pd.Index(df[keys[0]])
    found = proven.reindex(index).to_numpy(dtype=float)
    if "optimum" in df.columns:
        df["optimum"] = np.where(np.isfinite(df["optimum"].to_numpy(float)), df["optimum"], found)
    else:
        df["optimum"] = found
    df["exact_bound"] = bound.reindex(index).to_numpy(dtype=float)
    return df
