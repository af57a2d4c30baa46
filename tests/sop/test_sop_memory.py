"""The SOP portfolio's memory estimate (issue 33): monotone in the limit and the state cap,
never above the memory limit it guards, CP-SAT's worker counted exactly when it runs, and a
small limit degrading the run instead of refusing it."""

from __future__ import annotations

import pytest

import taopt
import taopt.heuristics  # noqa: F401  (registers the CP-SAT peer the portfolio looks up)
from taopt.heuristics import peers
from taopt.models import sop as sop_model
from taopt.models.sop import (
    BASE_BYTES,
    _cpsat_peer,
    _footprint,
    _stage_limit,
    cpsat_worker_bytes,
    dp_bytes,
    dp_state_cap,
    solve_sop_problem,
)
from taopt.models.sop_stages import MIN_DP_STATES, memory_plan
from taopt.result import OPTIMAL, TIME_LIMIT
from taopt.sop.generate import random_sop
from taopt.sop.problem import SopProblem, evaluate_order

pytest.importorskip("ortools")


@pytest.fixture(scope="module", autouse=True)
def stop_workers():
    """Stop the peer workers after this module, so no test leaves processes behind."""
    yield
    peers.shutdown()


@pytest.fixture(scope="module")
def esc25() -> SopProblem:
    """ESC25 (shipped): 27 nodes, order ideals past the count's cap (the DP's states are
    estimated by the rate and the caps, not by the ideals)."""
    return SopProblem.load("ESC25")


@pytest.fixture(scope="module")
def esc47() -> SopProblem:
    """ESC47 (shipped): 49 nodes, where CP-SAT runs beside by default."""
    return SopProblem.load("ESC47")


def test_estimate_is_monotone_in_the_time_limit(esc25):
    """A longer limit never lowers the guard's estimate (a DP stage keeps more states)."""
    estimates = [
        _footprint(esc25, {"time_limit": t, "cpsat": False})[0] for t in (1, 5, 10, 60, 600)
    ]
    assert estimates == sorted(estimates)
    assert estimates[-1] > estimates[0]


def test_estimate_is_monotone_in_the_state_cap(esc25):
    """A larger state cap never lowers the estimate of the DP alone (no time limit: the cap
    is what bounds it), and the DP part is at most the cap's bytes."""
    caps = (1_000, 10_000, 100_000, 1_000_000)
    options = {"engine": "dp", "cpsat": False}
    estimates = [_footprint(esc25, {**options, "max_states": c})[0] for c in caps]
    assert estimates == sorted(estimates)
    assert estimates[-1] > estimates[0]
    for cap, estimate in zip(caps, estimates, strict=True):
        assert estimate <= BASE_BYTES + dp_bytes(esc25.n, cap) + 1


def test_expected_states_grow_with_the_stage_and_fall_with_the_nodes():
    """A DP stage's expected states grow with its length (the rate at DP_RATE_SECONDS, less
    per second beyond), are none for no time, and fall beyond 64 nodes."""
    at = [sop_model.dp_states_in(50, t) for t in (0.0, 1.0, 5.0, 30.0, 60.0)]
    assert at[0] == 0.0 and at == sorted(at)
    rate = sop_model.DP_STATES_PER_SECOND
    assert at[2] == pytest.approx(rate * sop_model.DP_RATE_SECONDS)
    assert at[4] <= rate * 60.0
    assert sop_model.dp_states_in(128, 30.0) == pytest.approx(at[3] / 2)


def test_state_cap_is_monotone_in_the_memory_limit():
    """A larger memory limit never gives fewer states, and less room beside (a reserve for
    CP-SAT's worker) never gives more."""
    caps = [dp_state_cap(50, gb, 1 << 40) for gb in (0.3, 0.5, 1.0, 4.0, 16.0)]
    assert caps == sorted(caps)
    assert dp_state_cap(50, 1.0, 1 << 40, reserve=200e6) < dp_state_cap(50, 1.0, 1 << 40)


@pytest.mark.parametrize("gb", [0.05, 0.2, 0.4, 1.0, 4.0])
@pytest.mark.parametrize("cpsat", [False, True])
def test_guard_never_passes_a_plan_above_the_limit(esc25, gb, cpsat):
    """The guard's estimate is at most the limit, and when the DP runs its state cap (with
    CP-SAT's worker beside, if it runs) keeps the stage within the limit too."""
    options = {"time_limit": 60.0, "max_memory_gb": gb, "cpsat": cpsat}
    estimate, what = _footprint(esc25, options)
    assert estimate <= gb * 1e9
    peer, _ = _cpsat_peer(esc25, cpsat, "auto", 60.0, gb)
    reserve = 0.0 if peer is None else cpsat_worker_bytes(esc25.n)
    limit = _stage_limit(gb, reserve)
    if memory_plan(esc25.n, limit) == "dp":
        cap = dp_state_cap(esc25.n, limit, 1 << 40)
        assert cap >= MIN_DP_STATES
        assert BASE_BYTES + reserve + dp_bytes(esc25.n, cap) <= gb * 1e9
    else:
        assert "degraded" in what


def test_cpsat_worker_is_counted_only_when_it_runs(esc25):
    """With room to spare the estimate with CP-SAT beside is the estimate without it plus
    the worker's, and the guard's description names it."""
    on, what_on = _footprint(esc25, {"time_limit": 10.0, "cpsat": True, "max_memory_gb": 64})
    off, what_off = _footprint(esc25, {"time_limit": 10.0, "cpsat": False, "max_memory_gb": 64})
    assert on == pytest.approx(off + cpsat_worker_bytes(esc25.n))
    assert "CP-SAT" in what_on and "CP-SAT" not in what_off


def test_cpsat_worker_grows_with_the_nodes():
    """The worker's estimate is its base on a few nodes and grows with n."""
    assert cpsat_worker_bytes(10) < cpsat_worker_bytes(100) < cpsat_worker_bytes(400)
    assert cpsat_worker_bytes(10) >= sop_model.CPSAT_WORKER_BYTES


def test_cpsat_stays_off_when_its_worker_leaves_no_room_for_the_dp(esc47):
    """By default CP-SAT is not started when the limit less its worker would push the DP
    down the memory ladder; the reason names the memory. cpsat=True still starts it."""
    tight = (BASE_BYTES + dp_bytes(esc47.n, 2 * MIN_DP_STATES)) / 1e9
    assert memory_plan(esc47.n, tight) == "dp"
    peer, why = _cpsat_peer(esc47, None, "auto", 60.0, tight)
    assert peer is None and "memory limit" in why
    peer, _ = _cpsat_peer(esc47, None, "auto", 60.0, 64.0)
    assert peer is not None
    peer, _ = _cpsat_peer(esc47, True, "auto", 60.0, tight)
    assert peer is not None


def test_run_with_cpsat_records_the_worker_in_its_estimate():
    """A run with CP-SAT beside counts the worker in ``info["memory_estimate"]`` (and says
    how much in ``info["cpsat"]``); without CP-SAT it does not."""
    problem = random_sop(10, 0.2, 3)
    on = solve_sop_problem(problem, time_limit=20.0, cpsat=True)
    off = solve_sop_problem(problem, time_limit=20.0, cpsat=False)
    worker = cpsat_worker_bytes(problem.n)
    assert on.info["cpsat"]["memory_estimate"] == pytest.approx(worker)
    assert on.info["memory_estimate"] >= BASE_BYTES + worker
    assert off.info["cpsat"] == "off"
    assert off.info["memory_estimate"] < BASE_BYTES + worker
    assert on.status == off.status == OPTIMAL and on.objective == off.objective


def test_small_limit_degrades_instead_of_refusing(esc47):
    """With a memory limit below the DP's the portfolio (CP-SAT off by the memory rule)
    returns a feasible order and a bound, status time_limit or optimal, no InstanceError,
    and its recorded estimate stays within the limit."""
    gb = (BASE_BYTES + dp_bytes(esc47.n, MIN_DP_STATES // 4)) / 1e9
    result = taopt.solve(esc47, "exact", time_limit=1.0, max_memory_gb=gb)
    assert result.info["memory_plan"] != "dp"
    assert str(result.info["cpsat"]).startswith("off")
    assert result.status in (TIME_LIMIT, OPTIMAL)
    assert evaluate_order(esc47, result.order) == result.objective
    assert result.bound is not None and result.bound <= result.objective
    assert result.info["memory_estimate"] <= gb * 1e9


@pytest.mark.parametrize("limit", [1.0, 10.0, 60.0])
@pytest.mark.parametrize("path", ["dp", "root+dp", "cuts"])
def test_guard_is_never_below_the_reported_estimate(esc47, limit, path):
    """The guard made before the run is at least the estimate predicted before the stages,
    whatever path the rule takes and the time the stages get within the limit."""
    from taopt.models.sop import PORTFOLIO_MAX_STATES, nonzero_count, predicted_peak

    guard, _ = _footprint(esc47, {"time_limit": limit, "cpsat": False})
    nonzeros = 0 if path == "dp" else nonzero_count(esc47.cost, esc47.closure, esc47.start, "cuts")
    for seconds in (0.0, 0.01 * limit, 0.5 * limit, limit):
        for cut_seconds in (0.0, seconds, limit):
            estimate, _ = predicted_peak(
                esc47, path, seconds, PORTFOLIO_MAX_STATES, None, nonzeros, cut_seconds
            )
            assert estimate <= guard


def test_run_reports_an_estimate_within_its_guard(esc25):
    """A portfolio run's reported estimate (predicted before its stages) is at most the
    guard's for the same call, and above the process's base."""
    guard, _ = _footprint(esc25, {"time_limit": 1.0, "cpsat": False})
    result = solve_sop_problem(esc25, time_limit=1.0, cpsat=False)
    assert BASE_BYTES <= result.info["memory_estimate"] <= guard
    if result.info["engine"] != "none":  # a stage ran: the rule predicted before it
        assert result.info["memory_prediction"]["path"] in ("dp", "root+dp", "cuts")


def test_estimate_is_monotone_in_its_inputs(esc47):
    """The reported estimate never falls as the DP's time, its cap, the states the ideals
    allow or the cut engine's time grow, and the DP's states never pass its cap."""
    from taopt.models.sop import nonzero_count, predicted_peak, predicted_states

    nz = nonzero_count(esc47.cost, esc47.closure, esc47.start, "cuts")

    def at(**change):
        args = dict(seconds=30.0, cap=2_000_000, allowed=None, cut=60.0) | change
        return predicted_peak(
            esc47, "root+dp", args["seconds"], args["cap"], args["allowed"], nz, args["cut"]
        )[0]

    for key, values in (
        ("seconds", (0.0, 1.0, 10.0, 60.0, 600.0)),
        ("cap", (1_000, 100_000, 2_000_000)),
        ("allowed", (1e3, 1e5, 1e7)),
        ("cut", (1.0, 10.0, 60.0, 600.0)),
    ):
        estimates = [at(**{key: v}) for v in values]
        assert estimates == sorted(estimates), key
    assert predicted_states(esc47.n, 600.0, 5_000, None) == 5_000
    assert predicted_states(esc47.n, None, 5_000, 1e3) <= 1e3


def test_cut_engine_estimate_grows_with_its_arcs_and_time():
    """The cut engine's estimate is 0 without a model, then grows with the arcs and the
    seconds, its MIP rounds counted in full from CUT_MIP_ARCS arcs on."""
    from taopt.models.sop import CUT_MIP_ARCS, SOP_MILP_BYTES, cut_engine_bytes

    assert cut_engine_bytes(0, 60.0) == 0.0
    assert cut_engine_bytes(3 * 100, 0.0) > SOP_MILP_BYTES
    by_arcs = [cut_engine_bytes(3 * a, 10.0) for a in (100, 1_000, CUT_MIP_ARCS, 20_000)]
    by_time = [cut_engine_bytes(3 * 2_000, t) for t in (0.0, 1.0, 10.0, 60.0, None)]
    assert by_arcs == sorted(by_arcs) and by_time == sorted(by_time)


def test_guard_counts_the_cut_engine_and_skips_it_when_it_does_not_fit(esc47):
    """With room the guard counts the cut engine's MIP rounds over the limit (at the
    guard's factor); under a limit that fits the DP but not those, the cut engine is
    skipped (milp_fits), the run degrades to the DP instead of refusing."""
    from taopt.models.sop import CUT_GUARD_FACTOR, cut_engine_bytes, milp_fits, nonzero_count

    nz = nonzero_count(esc47.cost, esc47.closure, esc47.start, "cuts")
    roomy, what = _footprint(esc47, {"time_limit": 60.0, "cpsat": False, "max_memory_gb": 64})
    assert roomy >= BASE_BYTES + CUT_GUARD_FACTOR * cut_engine_bytes(nz, 60.0)
    assert "cuts model" in what
    tight = (BASE_BYTES + cut_engine_bytes(nz, 0.0) + dp_bytes(esc47.n, 20_000)) / 1e9
    assert not milp_fits(esc47, "cuts", tight, 60.0)
    assert memory_plan(esc47.n, tight) == "dp"
    estimate, what = _footprint(esc47, {"time_limit": 60.0, "cpsat": False, "max_memory_gb": tight})
    assert estimate <= tight * 1e9 and "cuts model" not in what


def test_solve_counts_the_ideals_once(monkeypatch):
    """taopt.solve's guard counts the ideals and the run that follows takes its count (one
    count per call, on the call's clock); a direct portfolio call counts for itself."""
    from taopt.models import sop_dp

    problem = random_sop(12, 0.2, 5)
    calls = []
    real = sop_dp.count_ideals

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(sop_dp, "count_ideals", counted)
    result = taopt.solve(problem, "exact", time_limit=5.0, cpsat=False)
    assert len(calls) == 1 and result.status == OPTIMAL
    again = solve_sop_problem(problem, time_limit=5.0, cpsat=False)
    assert len(calls) == 2 and again.objective == result.objective


def _probe(forward, backward, finished=False):
    """A :class:`~taopt.models.sop.Probe` of these layer sizes (states: their sum)."""
    from taopt.models.sop import Probe

    return Probe(tuple(forward), tuple(backward), finished, sum(forward) + sum(backward), 0.1)


#: Probes of the first layers as measured on the shipped files (closing: slow growth;
#: filling: tens of times a layer; shrinking; one direction empty; finished).
PROBES = {
    "slow": ([1, 24, 39, 64, 100, 180, 282, 419, 554, 745], [1, 36, 97, 204, 384, 732]),
    "explosive": ([1, 37, 1327], [1, 36, 1238, 20568]),
    "shrinking": ([1, 30, 20, 12, 8], [1, 25, 14, 9]),
    "empty": ([1, 5, 0], [1, 4, 3]),
    "one layer": ([1], [1]),
}


@pytest.mark.parametrize("kind", sorted(PROBES))
@pytest.mark.parametrize("n", [20, 49, 120])
def test_probe_extrapolation_is_never_below_what_it_measured(kind, n):
    """The probe's extrapolation is at least the states it measured, exactly them when the
    probe finished (or a direction kept nothing), and finite."""
    import math

    from taopt.models.sop import probe_extrapolation

    forward, backward = PROBES[kind]
    probe = _probe(forward, backward)
    extrapolated = probe_extrapolation(n, probe)
    assert math.isfinite(extrapolated) and extrapolated >= probe.states
    assert probe_extrapolation(n, _probe(forward, backward, finished=True)) == probe.states
    if kind == "empty":
        assert extrapolated == probe.states


def test_probe_extrapolation_grows_with_the_growth_and_the_layers_left():
    """Faster growth of the last layers, or more layers left to the middle, never lowers the
    extrapolation; explosive growth extrapolates far beyond slow growth."""
    from taopt.models.sop import probe_extrapolation

    slow = _probe([1, 10, 100, 200], [1, 10, 100, 200])
    fast = _probe([1, 10, 100, 1000], [1, 10, 100, 1000])
    assert probe_extrapolation(49, fast) > 10 * probe_extrapolation(49, slow)
    by_n = [probe_extrapolation(n, slow) for n in (10, 20, 49, 100)]
    assert by_n == sorted(by_n)


def test_probe_states_keep_within_the_cap_the_ideals_and_the_fill():
    """The states predicted after a probe are at most the stage's cap and the states the
    ideals allow, at most what a filling stage keeps in its time unless the probe measured
    more, fewer with CP-SAT beside, and never below the probe's states under the cap."""
    from taopt.models.sop import fill_states, probe_states

    explosive = _probe(*PROBES["explosive"])
    fill = fill_states(49, 10.0, False)
    assert probe_states(49, explosive, 10.0, 1e9, None, False) == pytest.approx(fill)
    assert probe_states(49, explosive, 10.0, 1e9, None, True) < fill
    assert probe_states(49, explosive, 10.0, 5_000, None, False) == 5_000
    assert probe_states(49, explosive, 10.0, 1e9, 3_000.0, False) == 3_000
    assert probe_states(49, explosive, 1e-6, 1e9, None, False) == explosive.states
    times = [probe_states(49, explosive, t, 1e9, None, False) for t in (0.1, 1.0, 10.0, 60.0)]
    assert times == sorted(times)


def test_fill_states_grow_with_the_time_and_fall_beside_cpsat():
    """A filling stage keeps more states the longer it runs, none in no time, fewer beside
    CP-SAT's worker and fewer a second beyond 64 nodes; no limit: unbounded."""
    from taopt.models.sop import fill_states

    at = [fill_states(49, t, False) for t in (0.0, 1.0, 10.0, 60.0)]
    assert at[0] == 0.0 and at == sorted(at) and at[-1] > at[1]
    assert fill_states(49, 10.0, True) < at[2]
    assert fill_states(256, 10.0, False) == pytest.approx(at[2] / 2)
    assert fill_states(49, None, False) == float("inf")


@pytest.mark.parametrize("limit", [1.0, 10.0, 60.0])
@pytest.mark.parametrize("kind", sorted(PROBES))
def test_guard_is_never_below_an_estimate_made_from_a_probe(esc47, limit, kind):
    """The guard is at least the estimate made from any probe of the first DP stage (with or
    without CP-SAT beside, the DP alone or after the root stage) whose states a stage could
    keep in the limit."""
    from taopt.models.sop import (
        PORTFOLIO_MAX_STATES,
        fill_states,
        nonzero_count,
        predicted_peak,
    )

    probe = _probe(*PROBES[kind])
    assert probe.states <= fill_states(esc47.n, limit, False)
    guard, _ = _footprint(esc47, {"time_limit": limit, "cpsat": False})
    nonzeros = nonzero_count(esc47.cost, esc47.closure, esc47.start, "cuts")
    for path, held in (("dp", 0), ("root+dp", nonzeros)):
        for seconds in (0.01 * limit, 0.5 * limit, limit):
            for beside in (False, True):
                estimate, features = predicted_peak(
                    esc47, path, seconds, PORTFOLIO_MAX_STATES, None, held, 0.0, probe, beside
                )
                assert estimate <= guard
                assert features["probe"]["extrapolated"] >= probe.states


def test_layer_watch_reads_the_first_layers_of_the_dp():
    """The watch handed to the DP sees both directions' first layers once (layer 0 of one
    state each), never more states than the stage kept, and a DP that closes within its
    time is seen finished."""
    from taopt.models.sop import LayerWatch
    from taopt.models.sop_dp import solve_sop_dp

    problem = SopProblem.load("ESC12")
    seen = []
    result = solve_sop_dp(problem, incumbent=None, watch=LayerWatch(60.0, seen.append))
    assert result.status == OPTIMAL
    assert len(seen) == 1
    probe = seen[0]
    assert probe.finished and probe.forward[0] == probe.backward[0] == 1
    assert probe.states <= result.info["states"]
    stopped = []
    watch = LayerWatch(60.0, stopped.append, max_states=20)
    solve_sop_dp(problem, watch=watch)
    assert len(stopped) == 1 and stopped[0].states >= 20 and not stopped[0].finished
    watch.close()  # closed already: nothing more
    assert len(stopped) == 1


def test_run_records_the_probe_before_its_later_stages(esc25, monkeypatch):
    """A portfolio run whose DP stage ran records its estimate from the probe of that stage's
    first layers (layer sizes, states measured, extrapolated), within the guard (a 10 s limit:
    ESC25 closes in about 1 s, and at 2 s a loaded machine could stop it before its DP began).
    The DP stage first (TREE_FIRST off: ESC25's root loop is complete, so the tree would go
    first and no DP stage would run)."""
    from taopt.models import sop

    monkeypatch.setattr(sop, "TREE_FIRST", False)
    guard, _ = _footprint(esc25, {"time_limit": 10.0, "cpsat": False})
    result = solve_sop_problem(esc25, time_limit=10.0, cpsat=False)
    prediction = result.info["memory_prediction"]
    assert prediction["path"] in ("dp", "root+dp")
    probe = prediction["probe"]
    assert isinstance(probe, dict), probe
    assert probe["extrapolated"] >= probe["states"] >= 1
    assert BASE_BYTES <= result.info["memory_estimate"] <= guard


def test_probe_extrapolation_advances_the_smaller_direction():
    """As in the DP, the layers left go to the direction whose last layer is smaller: a
    slowly growing small direction beside an explosive large one extrapolates far below two
    explosive directions (rbg048a's probe: it closed with 94,000 states)."""
    from taopt.models.sop import probe_extrapolation

    one_fast = _probe([1, 10, 257, 1282, 5397], [1, 10, 1240, 1889, 2850])
    both_fast = _probe([1, 10, 257, 1282, 5397], [1, 10, 257, 1282, 5397])
    assert probe_extrapolation(50, one_fast) < probe_extrapolation(50, both_fast) / 10


@pytest.mark.parametrize("n", [49, 64, 65, 130, 200])
def test_expected_fill_counts_a_states_mask_words(n):
    """The reported estimate's filling DP stage keeps the guard's fill rate up to 64 nodes and
    that rate divided by the mask's words beyond (a state's bound work grows with them)."""
    from taopt.ideals import words
    from taopt.models.sop import expected_fill, fill_states

    fill = fill_states(n, 60.0, False, 0.5)
    want = fill if n <= 64 else fill / words(n)
    assert expected_fill(n, 60.0, False, 0.5) == pytest.approx(want)
    assert expected_fill(n, None, False) == float("inf")
