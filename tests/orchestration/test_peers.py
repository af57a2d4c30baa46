"""PyVRP and OR-Tools peers: feasible, never below the certified optimum, run out of process.

The exact optimum comes from ``taopt.models.solve_routing`` in this process
(which imports highspy); the peers run in worker processes, so the checks also
show that the two never meet in one process.
"""

from __future__ import annotations

import math
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import routing_idle_vehicle, routing_one_way, routing_quick_tour

import taopt
from taopt.errors import InstanceError, SolverError
from taopt.heuristics import peers
from taopt.heuristics.peers import ortools_solve, pyvrp_solve
from taopt.models import solve_routing
from taopt.navigation import uniform_travel_times
from taopt.registry import get_method
from taopt.sop.problem import evaluate_order
from taopt.status import decide

# Deterministic limits (iterations / solutions, not time) for everything but the n50m10 check.
SOLVERS = {
    "pyvrp": lambda p, **kw: pyvrp_solve(p, time_limit=None, max_iterations=300, **kw),
    "ortools": lambda p, **kw: ortools_solve(p, time_limit=None, solution_limit=300, **kw),
}
RELATIVE = 1e-6  # exact optimum certified to this gap; scaling error is ~5e-8 (n + m) relative


def uniform_current_problem(n: int, m: int, seed: int) -> taopt.AssignmentProblem:
    """Harness: n targets then m vehicles uniform in a 1000 m square, current (0.3, 0.1), v = 1."""
    rng = np.random.default_rng(seed)
    points = np.vstack([rng.uniform(0, 1000, (n, 2)), rng.uniform(0, 1000, (m, 2))])
    times = uniform_travel_times((0.3, 0.1), points[:, None], points[None, :], speed=1.0)
    return taopt.AssignmentProblem(times, n, name=f"uniform-n{n}m{m}-seed{seed}")


#: The hand-made chapter 2 references with a unique optimal routing (tests/reference.py).
REFERENCES = [routing_one_way, routing_idle_vehicle, routing_quick_tour]


def assert_not_below(solution: taopt.Solution, exact: taopt.Solution) -> None:
    """The peer's re-scored objective is at least the proven lower bound of the exact model."""
    assert solution.objective >= exact.bound * (1 - 1e-9) - 1e-9, (solution.objective, exact.bound)


@pytest.fixture(scope="module", autouse=True)
def stop_workers():
    """Stop the peer workers after this module, so no test leaves processes behind."""
    yield
    peers.shutdown()


@pytest.mark.parametrize("peer", sorted(SOLVERS))
@pytest.mark.parametrize("reference", REFERENCES, ids=lambda f: f.__name__)
def test_reference_problems_hit_known_optimum(peer, reference):
    """Each peer returns the known optimum and routes of the hand-made reference problems."""
    ref = reference()
    problem, optimum, routes = ref.problem, ref.optimum, ref.solution
    solution = SOLVERS[peer](problem)
    assert solution.status == "feasible" and solution.method == peer and solution.bound is None
    assert solution.objective == pytest.approx(optimum, rel=RELATIVE)
    assert solution.routes == routes
    assert solution.objective == taopt.evaluate(problem, solution.routes)


@pytest.mark.parametrize("peer", sorted(SOLVERS))
def test_direction_matters(peer):
    """On an asymmetric matrix and its transpose the peers find the two different optima."""
    rng = np.random.default_rng(11)
    cost = rng.uniform(1, 10, (8, 8))
    cost[np.triu_indices(8, 1)] *= 20  # forward arcs between low indices are dear, backward cheap
    problem, reverse = taopt.AssignmentProblem(cost, 6), taopt.AssignmentProblem(cost.T, 6)
    for case in (problem, reverse):
        exact = solve_routing(case)
        solution = SOLVERS[peer](case)
        assert exact.status == "optimal"
        assert solution.objective == pytest.approx(exact.objective, rel=RELATIVE)
    assert solve_routing(problem).objective != pytest.approx(solve_routing(reverse).objective)


SMALL = [(4, 2, 0), (6, 1, 1), (7, 3, 2), (8, 2, 3), (9, 3, 4), (9, 1, 5), (5, 5, 6)]


@pytest.mark.parametrize("peer", sorted(SOLVERS))
@pytest.mark.parametrize("n, m, seed", SMALL)
def test_small_instances_feasible_and_not_below_optimum(peer, n, m, seed):
    """n <= 9: feasible, re-scored, never below the certified optimum; equal to it when m = 1 or n <= 4."""
    problem = uniform_current_problem(n, m, seed)
    exact = solve_routing(problem)
    assert exact.status == "optimal"
    solution = SOLVERS[peer](problem)
    assert solution.objective == taopt.evaluate(problem, solution.routes)
    assert_not_below(solution, exact)
    if m == 1 or n <= 4:
        assert solution.objective == pytest.approx(exact.objective, rel=RELATIVE)


@settings(max_examples=12, deadline=None, derandomize=True)
@given(
    n=st.integers(1, 6),
    m=st.integers(1, 3),
    seed=st.integers(0, 2**16),
    peer=st.sampled_from(sorted(SOLVERS)),
)
def test_random_asymmetric_matrices_never_below_optimum(n, m, seed, peer):
    """Random non-metric asymmetric costs (with zeros): feasible and never below the optimum."""
    rng = np.random.default_rng(seed)
    cost = rng.integers(0, 50, (n + m, n + m)).astype(float)
    problem = taopt.AssignmentProblem(cost, n)
    exact = solve_routing(problem)
    solution = SOLVERS[peer](problem)
    assert solution.objective == taopt.evaluate(problem, solution.routes)
    assert_not_below(solution, exact)


@pytest.mark.parametrize("peer", sorted(SOLVERS))
def test_same_seed_same_result(peer):
    """Stopped by iterations (PyVRP) or solutions (OR-Tools), two runs agree bit for bit."""
    problem = uniform_current_problem(20, 4, 7)
    first, second = SOLVERS[peer](problem, seed=3), SOLVERS[peer](problem, seed=3)
    assert first.routes == second.routes and first.objective == second.objective
    assert first.info["solver_objective"] == second.info["solver_objective"]


@pytest.mark.parametrize("peer", sorted(SOLVERS))
def test_integer_objective_matches_float_within_rounding(peer):
    """The solver's integer objective is objective * scale within (n + m)/2 units (rounding)."""
    problem = uniform_current_problem(12, 3, 8)
    solution = SOLVERS[peer](problem)
    scale = solution.info["scale"]
    assert scale * problem.cost.max() == pytest.approx(peers.LARGEST_ENTRY)
    error = abs(solution.info["solver_objective"] - solution.objective * scale)
    assert error <= 0.5 * (problem.n + problem.m)


def test_highs_survives_peer_calls():
    """After both peers ran, this process (which imports taopt.models) still has HIGHS in cvxpy."""
    import cvxpy

    import taopt.models  # noqa: F401  (imports highspy)

    problem = uniform_current_problem(6, 2, 9)
    for solve in SOLVERS.values():
        solve(problem)
    assert "HIGHS" in cvxpy.installed_solvers()
    # (import cvxpy imports the bare ``ortools`` package; its native libraries stay out)
    assert "ortools.constraint_solver.pywrapcp" not in sys.modules and "pyvrp" not in sys.modules
    assert solve_routing(problem).status == "optimal"


def run_script(code: str, **kwargs) -> subprocess.Popen:
    """Start ``python -c code`` with this interpreter, its stdout piped.

    It runs outside the checkout (``python -c`` puts the working folder first on sys.path,
    where the source tree would shadow the installed package)."""
    kwargs.setdefault("cwd", tempfile.gettempdir())
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def test_script_importing_models_at_top_can_use_ortools(tmp_path: Path):
    """A script that imports taopt.models (highspy) at its top still gets OR-Tools results."""
    script = tmp_path / "study.py"
    script.write_text(
        textwrap.dedent(
            """
            import numpy as np
            import taopt
            import taopt.models
            from taopt.heuristics.peers import ortools_solve

            if __name__ == "__main__":
                cost = np.array([[0, 2, 9], [1, 0, 9], [4, 3, 0]], dtype=float)
                problem = taopt.AssignmentProblem(cost, 2)
                exact = taopt.models.solve_routing(problem).objective
                print(ortools_solve(problem, time_limit=None, solution_limit=20).objective, exact)
            """
        )
    )
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["4.0", "4.0"]


def missing_package_message(monkeypatch, peer: str) -> str:
    """The SolverError message of ``peer`` when its package is not found."""
    monkeypatch.setattr(peers, "_find_spec", lambda name: None if name == peer else object())
    with pytest.raises(SolverError) as info:
        SOLVERS[peer](routing_quick_tour().problem)
    return str(info.value)


@pytest.mark.parametrize("peer", sorted(SOLVERS))
def test_missing_package_says_how_to_install(monkeypatch, peer):
    """A peer package that is not installed gives a SolverError with the pip command."""
    message = missing_package_message(monkeypatch, peer)
    assert peer in message and 'pip install "taopt[peers]"' in message


def test_broken_package_in_worker_says_how_to_install(
    monkeypatch, tmp_path: Path, ref_routing_quick_tour
):
    """A peer package that fails to import inside the worker gives the same pip hint."""
    fake = tmp_path / "pyvrp"
    fake.mkdir()
    (fake / "__init__.py").write_text("raise ImportError('this pyvrp is broken')\n")
    peers.shutdown()
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    try:
        with pytest.raises(SolverError, match=r'pyvrp.*broken.*pip install "taopt\[peers\]"'):
            SOLVERS["pyvrp"](ref_routing_quick_tour.problem)
    finally:
        monkeypatch.delenv("PYTHONPATH")
        peers.shutdown()
    assert SOLVERS["pyvrp"](ref_routing_quick_tour.problem).objective == 4.0


def test_worker_crash_is_a_solver_error_and_worker_restarts():
    """Killing the OR-Tools worker mid-solve raises a SolverError naming it; the next call works."""
    problem = uniform_current_problem(40, 5, 10)
    ortools_solve(problem, time_limit=0.1)  # the worker is up
    pid = peers._WORKERS["ortools"].process.pid
    threading.Timer(1.0, os.kill, (pid, signal.SIGKILL)).start()
    with pytest.raises(SolverError, match="ortools worker process died"):
        ortools_solve(problem, time_limit=30, no_improvement=None)  # runs until killed
    assert ortools_solve(problem, time_limit=0.1).objective > 0
    assert peers._WORKERS["ortools"].process.pid != pid


def test_overrun_stops_the_worker_and_answers_with_its_best(monkeypatch):
    """A worker that has not answered by the limit plus the grace is stopped; the call answers
    with the last solution it reported (scored) or no_solution, never an exception, and the
    next call starts a fresh worker."""
    problem = uniform_current_problem(30, 4, 12)
    ortools_solve(problem, time_limit=0.1)
    pid = peers._WORKERS["ortools"].process.pid
    monkeypatch.setattr(peers, "GRACE", -0.7)  # wait 0.3 s for a 1 s search
    stopped = ortools_solve(problem, time_limit=1.0, no_improvement=None)
    assert "stopped it" in stopped.info["worker"]
    assert stopped.info["stopped_by"] == "time_limit"
    if stopped.status == "feasible":  # its first solution came back as a "best" frame
        assert taopt.evaluate(problem, stopped.solution) == pytest.approx(stopped.objective)
    else:
        assert stopped.status == "no_solution" and math.isinf(stopped.objective)
    assert wait_gone(pid, 5.0)
    monkeypatch.undo()
    assert ortools_solve(problem, time_limit=0.1).objective > 0
    assert peers._WORKERS["ortools"].process.pid != pid


def test_threads_share_a_worker():
    """Calls from several threads are served one at a time and give the sequential results."""
    problems = [uniform_current_problem(15, 3, seed) for seed in range(4)]
    expected = [SOLVERS["pyvrp"](p).routes for p in problems]
    found: dict[int, list] = {}
    threads = [
        threading.Thread(target=lambda k=k: found.update({k: SOLVERS["pyvrp"](problems[k]).routes}))
        for k in range(4)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert [found[k] for k in range(4)] == expected


def test_solver_failure_names_the_peer(ref_routing_quick_tour):
    """An option the solver rejects comes back as a SolverError naming OR-Tools."""
    with pytest.raises(SolverError, match="(?s)ortools failed.*unknown metaheuristic 'NOPE'"):
        ortools_solve(ref_routing_quick_tour.problem, metaheuristic="NOPE")


def test_a_time_limit_before_the_first_solution_is_a_status():
    """OR-Tools stopped by a 1 ms limit before its first route set gives status no_solution
    (objective inf, the reason in info["error"]), not an exception; given more time, it
    answers."""
    rng = np.random.default_rng(4)
    problem = taopt.AssignmentProblem(rng.uniform(1.0, 100.0, size=(70, 70)), 60)
    stopped = taopt.solve(problem, "ortools", time_limit=0.001)
    if stopped.status == "no_solution":
        assert stopped.solution is None and math.isinf(stopped.objective)
        assert "no route set within time_limit" in stopped.info["error"]
    else:  # a machine fast enough to find one in 1 ms: then it is a checked answer
        assert taopt.evaluate(problem, stopped.solution) == pytest.approx(stopped.objective)
    assert taopt.solve(problem, "ortools", time_limit=0.5).status == "feasible"


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: pyvrp_solve(p, time_limit=0), "time_limit"),
        (lambda p: pyvrp_solve(p, time_limit=None, no_improvement=None), "never stops"),
        (lambda p: pyvrp_solve(p, no_improvement=0), "no_improvement"),
        (lambda p: ortools_solve(p, no_improvement="soon"), "no_improvement"),
        (lambda p: ortools_solve(p, time_limit=None, solution_limit=0), "solution_limit"),
        (lambda p: pyvrp_solve(p, seed=-1), "seed"),
        (lambda p: ortools_solve(p, scale=-1.0), "scale"),
        (lambda p: ortools_solve(p, scale=1e15), "integer units"),
        (lambda p: pyvrp_solve(p.cost), "AssignmentProblem"),
    ],
)
def test_bad_arguments_are_clear(call, match, ref_routing_quick_tour):
    """Bad limits, seed, scale or problem type raise InstanceError before any worker runs."""
    with pytest.raises(InstanceError, match=match):
        call(ref_routing_quick_tour.problem)


def process_gone(pid: int) -> bool:
    """True when ``pid`` no longer runs (absent, or a zombie waiting to be reaped)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


def wait_gone(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if process_gone(pid):
            return True
        time.sleep(0.1)
    return process_gone(pid)


PARENT = """
    import sys
    import numpy as np
    import taopt
    from taopt.heuristics import peers
    from taopt.heuristics.peers import ortools_solve

    rng = np.random.default_rng(0)
    problem = taopt.AssignmentProblem(rng.uniform(1, 100, (45, 45)), 40)
    ortools_solve(problem, time_limit=0.1)
    print(peers._WORKERS["ortools"].process.pid, flush=True)
    ortools_solve(problem, time_limit=60, no_improvement=None)  # busy when the parent is stopped
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGINT], ids=["killed", "ctrl-c"])
def test_worker_dies_with_its_parent(how):
    """A busy worker does not outlive a parent that is killed or interrupted (no orphans).

    The parent starts with SIGINT at its default, as from a terminal: pytest run in the
    background (``cmd &`` in a script) passes SIGINT on ignored, and the parent would then
    never see the Ctrl-C (as test_study.py's study does)."""
    parent = run_script(PARENT, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    worker_pid = int(parent.stdout.readline())
    time.sleep(1.0)  # the 60 s solve is running
    assert not process_gone(worker_pid)
    parent.send_signal(how)
    parent.wait(timeout=30)
    assert wait_gone(worker_pid, 10.0)
    if how == signal.SIGINT:
        assert "KeyboardInterrupt" in parent.stderr.read()


@pytest.mark.parametrize("seed", range(5))  # ~3 s each (exact + 2 x 1 s)
def test_n50m10_one_second_not_below_certified_optimum(seed):
    """Harness n50m10, time_limit = 1 s: both peers feasible and never below the certified optimum."""
    problem = uniform_current_problem(50, 10, seed)
    exact = solve_routing(problem)
    assert exact.status == "optimal"
    for solve in (pyvrp_solve, ortools_solve):
        solution = solve(problem, time_limit=1.0, seed=seed)
        assert solution.objective == taopt.evaluate(problem, solution.routes)
        assert_not_below(solution, exact)


# ----------------------------------------------------------------------------- CP-SAT
def random_sop(seed: int, n: int) -> taopt.SopProblem:
    """Random integer SOP with 10 % forbidden arcs and a few precedences (always feasible
    once the arcs along one precedence-respecting order are restored)."""
    rng = np.random.default_rng([7, seed])
    cost = rng.integers(1, 40, (n, n)).astype(float)
    cost[rng.random((n, n)) < 0.1] = np.inf
    np.fill_diagonal(cost, 0.0)
    inner = [int(v) for v in rng.permutation(np.arange(1, n - 1))]
    pairs = [(inner[a], inner[a + 2]) for a in range(0, n - 4, 2)]
    path = [0, *inner, n - 1]
    cost[path[:-1], path[1:]] = rng.integers(1, 40, n - 1)  # one feasible order
    return taopt.SopProblem(cost, tuple(pairs), 0, n - 1, name=f"sop-{seed}")


@pytest.mark.parametrize("seed", range(4))
def test_cpsat_agrees_with_exact_on_small_sop(seed):
    """cpsat proves the same SOP optimum as taopt's exact portfolio; order re-scored."""
    problem = random_sop(seed, 7 + seed)
    exact = taopt.solve(problem, "exact")
    solution = taopt.solve(problem, "cpsat", time_limit=30, seed=seed)
    assert exact.status == "optimal" and solution.status == "optimal"
    assert solution.method == "cpsat" and solution.info["cpsat_status"] == "OPTIMAL"
    assert solution.objective == exact.objective
    assert evaluate_order(problem, solution.order) == solution.objective
    assert solution.bound == pytest.approx(exact.objective)


def test_cpsat_certifies_a_shipped_tsplib_sop(ref_sop_esc12):
    """cpsat proves TSPLIB's optimum 1675 of ESC12 (bound = objective, integer scale 1)."""
    problem = ref_sop_esc12.problem
    solution = taopt.solve(problem, "cpsat", time_limit=30)
    assert (
        solution.status == "optimal"
        and solution.objective == ref_sop_esc12.optimum == solution.bound
    )
    assert solution.info["scale"] == 1.0 and solution.info["exact_scaling"]


@pytest.mark.parametrize("n, m, seed", [(4, 2, 0), (6, 1, 1), (7, 3, 2), (8, 2, 3)])
def test_cpsat_agrees_with_exact_on_small_routing(n, m, seed):
    """cpsat's circuit model of (2.2)-(2.5) proves the exact model's optimum (within scaling)."""
    problem = uniform_current_problem(n, m, seed)
    exact = solve_routing(problem)
    solution = taopt.solve(problem, "cpsat", time_limit=30, seed=seed)
    assert solution.status == "optimal" and len(solution.routes) == m
    assert solution.objective == taopt.evaluate(problem, solution.routes)
    assert solution.objective == pytest.approx(exact.objective, rel=RELATIVE)
    assert solution.bound <= exact.objective * (1 + 1e-12)  # rounded down: still valid
    assert_not_below(solution, exact)


def test_cpsat_keeps_idle_vehicles_and_direction():
    """The hand-made references (idle vehicle, one-way arcs) come out at their optima."""
    for reference in REFERENCES:
        ref = reference()
        problem, optimum, routes = ref.problem, ref.optimum, ref.solution
        solution = taopt.solve(problem, "cpsat", time_limit=30)
        assert solution.objective == pytest.approx(optimum, rel=RELATIVE)
        assert solution.routes == routes


def test_cpsat_same_seed_same_result():
    """Same seed, same answer (a proof is unique in value; the order too on this instance)."""
    problem = random_sop(9, 10)
    first = taopt.solve(problem, "cpsat", time_limit=30, seed=3, num_workers=1)
    second = taopt.solve(problem, "cpsat", time_limit=30, seed=3, num_workers=1)
    assert first.order == second.order and first.objective == second.objective


def test_cpsat_infeasible_sop_is_a_status():
    """An SOP with no feasible path: CP-SAT's INFEASIBLE becomes status "infeasible"."""
    cost = np.ones((4, 4))
    cost[1, 2] = cost[2, 3] = np.inf
    problem = taopt.SopProblem(cost, ((1, 2),), 0, 3)  # 1 before 2, then 2 -> 3 forbidden
    solution = taopt.solve(problem, "cpsat", time_limit=30)
    assert solution.status == "infeasible" and solution.solution is None


def test_cpsat_status_and_bound_mapping():
    """OPTIMAL -> optimal (gap closed), FEASIBLE/UNKNOWN -> time_limit; bound scaled back down."""

    def status(raw, objective=10.0, bound=10.0):
        return decide(raw, objective, bound, solver="cpsat", time_limited=True)[0]

    assert status("OPTIMAL") == "optimal"
    assert status("OPTIMAL", bound=9.0) == "feasible"  # the one rule: a gap is not optimal
    assert status("FEASIBLE", bound=9.0) == "time_limit"
    assert status("UNKNOWN", objective=math.inf, bound=None) == "time_limit"
    assert status("INFEASIBLE") == "infeasible"
    assert peers._scaled_bound({"best_bound": 1234.7}, 10.0, 0.0) == 123.4
    assert peers._scaled_bound({"best_bound": 1234.7}, 10.0, 2.0) == 123.2
    assert peers._scaled_bound({"best_bound": None}, 10.0, 0.0) is None


def test_cpsat_missing_ortools_fails_loudly(monkeypatch, ref_sop):
    """Without OR-Tools, cpsat raises a SolverError with the install hint (never a skip)."""
    monkeypatch.setattr(peers, "_find_spec", lambda name: None)
    with pytest.raises(SolverError, match=r"cpsat is not installed.*taopt\[peers\]"):
        peers.cpsat_sop(ref_sop.problem)


def test_cpsat_is_one_registration_per_family(ref_sop):
    """Each family's "cpsat" is its own registered function; neither takes the other's type."""
    routing = taopt.AssignmentProblem(np.array([[0, 4, 9], [4, 0, 9], [2, 3, 0.0]]), n_targets=2)
    assert get_method(ref_sop.problem, "cpsat").func is peers.cpsat_sop
    assert get_method(routing, "cpsat").func is peers.cpsat_routing
    with pytest.raises(InstanceError, match="no method 'cpsat' for BudgetedProblem"):
        get_method(taopt.BudgetedProblem(routing.cost, n_targets=2, capacity=[2]), "cpsat")


def test_cpsat_wrong_problem_type_is_clear(ref_sop):
    """A direct call with another family's problem (or a bare matrix) names the expected type."""
    routing = taopt.AssignmentProblem(np.array([[0, 4, 9], [4, 0, 9], [2, 3, 0.0]]), n_targets=2)
    budgeted = taopt.BudgetedProblem(routing.cost, n_targets=2, capacity=[2])
    with pytest.raises(InstanceError, match="CP-SAT model needs a taopt.SopProblem, got ndarray"):
        peers.cpsat_sop(ref_sop.problem.cost)
    with pytest.raises(
        InstanceError, match="CP-SAT model needs a taopt.SopProblem, got AssignmentProblem"
    ):
        peers.cpsat_sop(routing)
    with pytest.raises(InstanceError, match="AssignmentProblem, got BudgetedProblem"):
        peers.cpsat_routing(budgeted)
    with pytest.raises(InstanceError, match="AssignmentProblem, got SopProblem"):
        peers.cpsat_routing(ref_sop.problem)


def test_cpsat_bad_arguments_are_clear(ref_sop):
    """A bad seed, worker count or time limit is an InstanceError before any worker runs."""
    problem = ref_sop.problem
    with pytest.raises(InstanceError, match="num_workers"):
        peers.cpsat_sop(problem, num_workers=0)
    with pytest.raises(InstanceError, match="seed"):
        peers.cpsat_sop(problem, seed=-1)
    with pytest.raises(InstanceError, match="time_limit"):
        peers.cpsat_routing(routing_quick_tour().problem, time_limit=0)


# -- the default stop and the wall-clock limit (issue 30 items 4 and 7) -------------------------


def test_default_stop_scales_with_the_instance():
    """The default no-improvement count grows with n + m above a floor, per peer."""
    assert peers.default_no_improvement("pyvrp", 3, 2) == peers.NO_IMPROVEMENT_MIN["pyvrp"]
    assert peers.default_no_improvement("pyvrp", 200, 10) == 50 * 210
    assert peers.default_no_improvement("ortools", 3, 2) == peers.NO_IMPROVEMENT_MIN["ortools"]
    assert peers.default_no_improvement("ortools", 400, 10) == 410


def test_explicit_count_limit_switches_the_default_stop_off(ref_routing_quick_tour):
    """Given max_iterations / solution_limit (the studies' --peer-iterations), "auto" adds no
    no-improvement stop, so such runs stop exactly as before."""
    problem = ref_routing_quick_tour.problem
    assert peers.stop_options("pyvrp", problem, "max_iterations", 2000, "auto") == {
        "max_iterations": 2000,
        "no_improvement": None,
    }
    assert peers.stop_options("ortools", problem, "solution_limit", None, "auto") == {
        "solution_limit": None,
        "no_improvement": 100,
    }
    assert peers.stop_options("pyvrp", problem, "max_iterations", None, 7)["no_improvement"] == 7


@pytest.mark.parametrize("peer", ["pyvrp", "ortools"])
def test_example_stops_on_no_improvement_before_its_limit(peer, assignment_example):
    """On the README's 3-target example each heuristic peer stops on its no-improvement count,
    not on the (long) time limit: the count of iterations / solutions it ran says so."""
    problem = assignment_example
    patience = peers.default_no_improvement(peer, problem.n, problem.m)
    solution = taopt.solve(problem, peer, time_limit=600.0)
    assert solution.status == "feasible" and solution.objective == pytest.approx(10.5)
    assert solution.info["no_improvement"] == patience
    assert "worker" not in solution.info  # it answered by itself
    done = solution.info["iterations" if peer == "pyvrp" else "solutions"]
    assert patience <= done <= 3 * patience


@pytest.mark.parametrize("peer", ["pyvrp", "ortools"])
def test_default_stop_is_deterministic(peer):
    """Without a time limit the default stop (counted, not timed) gives the same routes."""
    problem = uniform_current_problem(25, 3, 5)
    solve = pyvrp_solve if peer == "pyvrp" else ortools_solve
    first = solve(problem, time_limit=None, seed=2)
    second = solve(problem, time_limit=None, seed=2)
    assert first.routes == second.routes and first.objective == second.objective


def expired_calls():
    """(name, call) for every peer of every family, each given a limit spent before it starts."""
    from taopt.heuristics import budgeted_peers

    routing = uniform_current_problem(12, 3, 1)
    budgeted = taopt.BudgetedProblem(routing.cost, n_targets=12, capacity=[5, 5, 5])
    sop = random_sop(2, 8)
    tiny = 1e-7
    return [
        ("pyvrp", lambda: pyvrp_solve(routing, time_limit=tiny)),
        ("ortools", lambda: ortools_solve(routing, time_limit=tiny)),
        ("cpsat-routing", lambda: peers.cpsat_routing(routing, time_limit=tiny)),
        ("cpsat-sop", lambda: peers.cpsat_sop(sop, time_limit=tiny)),
        ("pyvrp-budgeted", lambda: budgeted_peers.pyvrp_budgeted(budgeted, time_limit=tiny)),
        ("ortools-budgeted", lambda: budgeted_peers.ortools_budgeted(budgeted, time_limit=tiny)),
    ]


@pytest.mark.parametrize("index", range(6), ids=[name for name, _ in expired_calls()])
def test_an_expired_limit_answers_without_a_search(index):
    """A limit spent before the request is sent answers at once, with no exception: no plan,
    objective inf, a status (no_solution; CP-SAT's time_limit) and the reason in info."""
    name, call = expired_calls()[index]
    peer = name.split("-")[0]
    peers._worker(peer).wait_ready(None)  # up already: only the request's limit is spent
    solution = call()
    assert solution.solution is None and math.isinf(solution.objective)
    assert str(solution.status) == ("time_limit" if peer == "cpsat" else "no_solution")
    assert "time limit was spent before the request was sent" in solution.info["worker"]


def test_a_limit_that_ends_during_start_up_leaves_the_worker_starting(ref_routing_quick_tour):
    """A call whose limit ends while its worker imports its package answers no_solution at
    once; the worker goes on starting and serves the next call (same process)."""
    peers.shutdown()
    problem = ref_routing_quick_tour.problem
    first = pyvrp_solve(problem, time_limit=1e-7)
    assert first.status == "no_solution" and "still starting" in first.info["error"]
    pid = peers._WORKERS["pyvrp"].process.pid
    second = pyvrp_solve(problem, time_limit=None, max_iterations=50)
    assert second.objective == 4.0 and peers._WORKERS["pyvrp"].process.pid == pid


def test_cpsat_worker_stops_building_at_its_deadline():
    """The worker checks its deadline while it builds the CP-SAT model: sent a request whose
    time is spent, it replies at once with status UNKNOWN, no routes and where it stopped
    (the request goes straight to the worker process; OR-Tools never loads in this one)."""
    cost = np.rint(uniform_current_problem(40, 4, 3).cost).astype(np.int64)
    options = {"time_limit": 1e-6, "seed": 0, "num_workers": 1, "kind": "routing"}
    worker = peers._worker("cpsat")
    with worker.lock:
        assert worker.wait_ready(None)
        reply, answered = worker.call({"cost": cost, "n": 40, "m": 4, "options": options}, None)
    assert answered and reply["cpsat_status"] == "UNKNOWN" and reply["routes"] is None
    assert reply["stopped_during"] == "model building"


def test_reported_solutions_are_complete_route_sets():
    """Every improving solution a worker streams (kept if it is stopped at the deadline) is a
    complete route set whose integer cost is the one reported, for each routing peer."""
    problem = uniform_current_problem(12, 3, 8)
    cost, _ = peers.integer_costs(problem, None)
    for peer, options in (
        ("pyvrp", {"max_iterations": 300, "seed": 0}),
        ("ortools", {"solution_limit": 50, "first_solution": "PATH_CHEAPEST_ARC",
                     "metaheuristic": "GUIDED_LOCAL_SEARCH", "seed": 0}),
        ("cpsat", {"seed": 0, "num_workers": 1, "kind": "routing", "time_limit": 20.0}),
    ):  # fmt: skip
        worker = peers._worker(peer)
        request = {"cost": cost, "n": 12, "m": 3, "options": options}
        with worker.lock:
            assert worker.wait_ready(None)
            worker.process.stdin.write(pickle.dumps(request, protocol=pickle.HIGHEST_PROTOCOL))
            worker.process.stdin.flush()
            frames = []
            while not frames or frames[-1][0] == "best":
                frames.append(worker.next_frame(None, "a solve"))
        assert frames[-1][0] == "ok" and len(frames) >= 2, peer
        for _, payload in frames[:-1]:
            routes = payload["routes"]
            assert sorted(t for route in routes for t in route) == list(range(12)), peer
            walked = sum(
                cost[a, b]
                for k, route in enumerate(routes)
                for a, b in zip([12 + k, *route], route, strict=False)
            )
            assert walked == payload["objective"], peer
