"""taopt.export / `taopt export`: every MILP written as LP and MPS, re-solved from the file."""

from __future__ import annotations

import highspy
import numpy as np
import pytest
import reference
from reference_exact import routing_instance

import taopt
from taopt.errors import InstanceError
from taopt.orchestration.cli import main
from taopt.orchestration.export import MODELS, export, export_model
from taopt.orchestration.solving import load_problem_file

REL = 1e-6

#: The reference instances export is checked on; the delivery one takes seconds per file.
_SLOW = {"delivery-small"}


def _resolve(path) -> tuple[highspy.HighsModelStatus, float]:
    """Read a written file back into a fresh HiGHS and solve it to a zero gap."""
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    assert h.readModel(str(path)) == highspy.HighsStatus.kOk
    h.setOptionValue("mip_rel_gap", 0.0)
    h.run()
    return h.getModelStatus(), h.getInfo().objective_function_value


def _cases():
    for make in reference.REFERENCES:
        ref = make()
        for model in MODELS.get(type(ref.problem).__name__, ()):
            marks = [pytest.mark.slow] if ref.name in _SLOW else []
            yield pytest.param(ref, model, id=f"{ref.name}-{model}", marks=marks)


def _expected(ref, model: str) -> float:
    """The certified optimum; the printed chapter 3 model is the thesis's relaxation, so its
    file must give that relaxation's value (solve_capability(..., "printed"))."""
    if model == "printed":
        from taopt.models.capability import solve_capability

        return solve_capability(ref.problem, "printed").objective
    return ref.optimum


@pytest.mark.parametrize(("ref", "model"), list(_cases()))
@pytest.mark.parametrize("fmt", ["lp", "mps"])
def test_exported_file_resolves_to_the_optimum(ref, model, fmt, tmp_path):
    """HiGHS reads each exported model back and reaches the reference optimum (DFJ models:
    with the cut pool at the end of the cut loop)."""
    path = export(ref.problem, model, tmp_path / f"{model}.{fmt}")
    status, value = _resolve(path)
    assert status == highspy.HighsModelStatus.kOptimal
    assert value == pytest.approx(_expected(ref, model), rel=REL, abs=1e-9)


@pytest.mark.parametrize("fmt", ["lp", "mps"])
def test_small_delivery_exported_resolves(fmt, tmp_path):
    """A three-customer truck-drone MILP re-solved from its file equals taopt.solve's optimum."""
    from taopt.orchestration.checker import _delivery_random

    problem = _delivery_random(np.random.default_rng(3), 3)
    optimum = taopt.solve(problem, "exact").objective
    status, value = _resolve(export(problem, "milp", tmp_path / f"d.{fmt}"))
    assert status == highspy.HighsModelStatus.kOptimal
    assert value == pytest.approx(optimum, rel=REL)


@pytest.mark.parametrize("seed", [1, 4, 9])
def test_dfj_with_every_subset_resolves(seed, tmp_path):
    """cuts="all" writes every subtour row (2.5): the file alone gives the optimum."""
    problem = routing_instance(seed)
    path = export(problem, "dfj", tmp_path / "all.lp", cuts="all")
    status, value = _resolve(path)
    assert status == highspy.HighsModelStatus.kOptimal
    assert value == pytest.approx(taopt.solve(problem, "exact").objective, rel=REL, abs=1e-9)
    rows = path.read_text().count("eq2_5_dfj_")
    assert rows == 2**problem.n - problem.n - 1


def test_row_and_column_names_follow_the_thesis(ref_routing_asymmetric):
    """Row eq2_3_in_j holds exactly the arcs sigma_i_j into target j; eq2_4_out_i the arcs out
    of point i; MTZ rows are named by their arc."""
    problem = ref_routing_asymmetric.problem
    h = export_model(problem, "mtz")
    lp = h.getLp()
    cols, rows = list(lp.col_names_), list(lp.row_names_)
    matrix = np.zeros((lp.num_row_, lp.num_col_))
    start, index, value = lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_
    for c in range(lp.num_col_):
        matrix[index[start[c] : start[c + 1]], c] = value[start[c] : start[c + 1]]
    n, m = problem.n, problem.m
    for j in range(n):
        used = {cols[c] for c in np.flatnonzero(matrix[rows.index(f"eq2_3_in_{j}")])}
        assert used == {f"sigma_{i}_{j}" for i in range(n + m) if i != j}
    for i in range(n + m):
        used = {cols[c] for c in np.flatnonzero(matrix[rows.index(f"eq2_4_out_{i}")])}
        assert used == {f"sigma_{i}_{j}" for j in range(n) if j != i}
    assert "eq2_5_mtz_0_1" in rows and "u_0" in cols


def test_delivery_names_follow_the_thesis(tmp_path):
    """Chapter 5's columns are y_p_i_j_k, w_p_k_i, S_p, t_p, R_p; rows cite (5.x)."""
    from taopt.orchestration.checker import _delivery_random

    problem = _delivery_random(np.random.default_rng(1), 2)
    text = export(problem, "milp", tmp_path / "d.lp").read_text()
    for name in ("y_0_", "w_1_", "S_0", "t_1", "R_0", "eq5_2_", "eq5_1_", "eq5_3_", "eq5_5_"):
        assert name in text, name


@pytest.mark.parametrize(
    ("model", "message"),
    [("tsp", "choose one of dfj, mtz, flow"), ("milp", "choose one of dfj, mtz, flow")],
)
def test_unknown_model_lists_the_valid_names(model, message, ref_routing_small, tmp_path):
    """A model the family does not have is refused with the valid names."""
    with pytest.raises(InstanceError, match=message):
        export(ref_routing_small.problem, model, tmp_path / "x.lp")


def test_unknown_format_and_family_are_refused(ref_routing_small, ref_comm, tmp_path):
    """An unknown extension, or a family without a MILP, is an InstanceError naming it."""
    with pytest.raises(InstanceError, match="unknown format 'txt'"):
        export(ref_routing_small.problem, "mtz", tmp_path / "x.txt")
    with pytest.raises(InstanceError, match="no exportable MILP for a CommProblem"):
        export(ref_comm.problem, "mtz", tmp_path / "x.lp")
    assert not list(tmp_path.iterdir())


def test_cli_export_writes_the_file(capsys, tmp_path):
    """`taopt export example:NAME --model --format --out` writes a file HiGHS solves."""
    out = tmp_path / "routing.mps"
    code = main(
        ["export", "example:assignment_problem", "--model", "flow", "--format", "mps"]
        + ["--out", str(out), "--quiet"]
    )
    assert code == 0 and out.exists()
    assert "wrote" in capsys.readouterr().out
    problem, _ = load_problem_file("example:assignment_problem", progress=False)
    status, value = _resolve(out)
    assert status == highspy.HighsModelStatus.kOptimal
    assert value == pytest.approx(taopt.solve(problem, "exact").objective, rel=REL)


def test_cli_export_unknown_model_exits_2(capsys, tmp_path):
    """A bad --model is exit code 2 with the valid names."""
    code = main(
        ["export", "example:sop_problem", "--model", "dfj", "--out", str(tmp_path / "x.lp")]
    )
    assert code == 2
    assert "choose one of flow, mtz" in capsys.readouterr().err


def _rows_of(h) -> tuple[list[str], list[str], np.ndarray]:
    """Column names, row names and the dense matrix of a HiGHS model."""
    lp = h.getLp()
    matrix = np.zeros((lp.num_row_, lp.num_col_))
    start, index, value = lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_
    for c in range(lp.num_col_):
        matrix[index[start[c] : start[c + 1]], c] = value[start[c] : start[c + 1]]
    return list(lp.col_names_), list(lp.row_names_), matrix


def test_budgeted_names_follow_the_model():
    """The budgeted file: x_k_i_j columns; eq2_3_in_j holds the arcs into j of every vehicle,
    each eq2_5_dfj_<S> row only arcs inside S, one sec6_2_* row per limited vehicle."""
    refs = [make() for make in reference.REFERENCES]
    problem = next(r.problem for r in refs if type(r.problem).__name__ == "BudgetedProblem")
    cols, rows, matrix = _rows_of(export_model(problem, "arc-vehicle"))
    assert len(set(rows)) == len(rows) and all(c.startswith("x_") for c in cols)
    for j in range(problem.n):
        used = [cols[c] for c in np.flatnonzero(matrix[rows.index(f"eq2_3_in_{j}")])]
        assert used and all(name.endswith(f"_{j}") for name in used)
    for r, name in enumerate(rows):
        if name.startswith("eq2_5_dfj_"):
            inside = set(name.removeprefix("eq2_5_dfj_").split("_"))
            for c in np.flatnonzero(matrix[r]):
                _, _, tail, head = cols[c].split("_")
                assert {tail, head} <= inside
    limited = np.isfinite(problem.capacity).sum() + np.isfinite(problem.max_time).sum()
    assert sum(name.startswith("sec6_2_") for name in rows) == limited


def test_any_cvxpy_milp_keeps_its_sense_and_labels(tmp_path):
    """highs_model on a maximising cvxpy MILP: the file keeps 'max' and the optimum, a labelled
    row is named by its equation, an unlabelled one by its id."""
    import cvxpy as cp

    from taopt.orchestration.export import highs_model

    x = cp.Variable(2, integer=True, name="x")
    budget = (x[0] + x[1] <= 4.5).set_label("(9.1) budget")
    cap = x[0] <= 2
    model = cp.Problem(cp.Maximize(3 * x[0] + 2 * x[1] + 5), [budget, x >= 0, cap])
    model.solve(solver=cp.HIGHS)
    path = tmp_path / "max.lp"
    highs_model(model).writeModel(str(path))
    text = path.read_text()
    assert text.startswith("\\") and "\nmax\n" in text
    assert "eq9_1_budget_0:" in text and f"c{cap.id}_0:" in text
    status, value = _resolve(path)
    assert status == highspy.HighsModelStatus.kOptimal
    assert value == pytest.approx(model.value) == 15.0
