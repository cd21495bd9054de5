"""The benchmarks run (tiny configurations) and their equal-accuracy checks hold; the numbers are in
docs/benchmarks.md."""
import shutil

import numpy as np
import pytest

import flatstep as fs
from flatstep import bench
from flatstep.cli import main


def checks(report: bench.Report) -> dict[str, float]:
    return {what: value for what, value, _ in report.checks}


def test_target_reports_how_far_a_missed_target_is():
    assert bench.Target("speed-up", 500.0, 1000, True, "x").describe().endswith("MISSED by a factor 2.00")
    assert bench.Target("time", 250.0, 100, False, " ns").describe().endswith("MISSED by a factor 2.50")
    assert bench.Target("time", 50.0, 100, False, " ns").met


def test_race_times_every_case_per_unit_and_keeps_its_result():
    calls = {"a": 0, "b": 0}

    def case(name):
        def fn():
            calls[name] += 1
            return name
        return fn

    times, results = bench.race({"a": case("a"), "b": case("b")}, repeat=3, min_time=0.0, per={"b": 10})
    assert results == {"a": "a", "b": "b"}
    assert calls == {"a": 5, "b": 5}  # result + calibration + 3 rounds of one loop each
    assert set(times) == {"a", "b"} and all(t > 0 for t in times.values())
    with pytest.raises(ValueError, match="repeat=0"):
        bench.race({"a": case("a")}, repeat=0)


def test_python_control_plans_the_papers_psi_move():
    pytest.importorskip("control")
    motor, plan = fs.MotorParams.preset("paper"), fs.PAPER_PLAN
    t = np.linspace(plan.t0, plan.tf, 41)
    x, v = bench.control_point_to_point(motor, plan)(t)
    x_ref, v_ref = fs.flat_to_state(plan.flag(t), motor)
    # python-control solves the endpoint conditions by least squares on a matrix of condition ~2e10 (its
    # derivative rows scale as (tf - t0)^-k): the end angle is met to ~2e-10 rad, the whole move to < 1e-8.
    assert np.abs(x[3] - x_ref[3]).max() < 1e-8
    assert np.abs(v - v_ref).max() < 1e-6
    assert abs(x[3, -1] - plan.theta2) < 1e-9


def test_bench_plan_runs_and_both_planners_agree():
    pytest.importorskip("control")
    report = bench.bench_plan(repeat=1, n=41, min_time=0.0, stock_basis=False)
    c = checks(report)
    assert c["python-control vs flatstep: max |theta diff|"] < 1e-8
    assert c["python-control vs flatstep: max |voltage diff|"] < 1e-6
    assert c["C core vs NumPy: max |theta diff|"] < 1e-15
    assert report.ratio("flatstep NumPy reference") > 1  # python-control is the baseline
    assert "(a)" in report.format()


def test_loosest_tolerance_takes_the_first_passing_rung():
    runs = []
    rtol, err, result = bench.loosest_tolerance(lambda r: runs.append(r) or r * 10, lambda res: res, 1e-8,
                                                (1e-6, 1e-7, 1e-9, 1e-10))
    assert (rtol, err, result, runs) == (1e-9, 1e-8, 1e-8, [1e-6, 1e-7, 1e-9])
    with pytest.raises(ValueError, match="no rtol in"):
        bench.loosest_tolerance(lambda r: r, lambda res: 1.0, 1e-8, (1e-6, 1e-7))


def test_bench_closed_loop_compares_engines_at_equal_accuracy():
    pytest.importorskip("control")
    report = bench.bench_closed_loop(repeat=1, dt_out=1e-4, min_time=0.0, ladder=(1e-7, 1e-8, 1e-9, 1e-10))
    errors = [t for t in report.targets if t.what.endswith("theta error")]
    assert len(errors) >= 5  # baseline, LSODA and python-control at their loosest, C end to end, C run loop
    assert all(t.met for t in errors), [t.describe() for t in errors]
    chosen = [what for what, _, _ in report.checks if "loosest rtol" in what]
    assert len(chosen) == 3 and report.baseline == "scipy LSODA, rtol 1e-10 (baseline)"
    assert any(t.what.startswith("speed-up of the C engine (end to end, equal accuracy)") for t in report.targets)


def test_bench_step_driver_counts_instructions():
    report = bench.bench_step(repeat=1, calls=2000, callgrind_calls=200, n=64, min_time=0.0)
    c = checks(report)
    assert c["max |v_C - v_NumPy| on the inputs"] < 1e-12
    assert c["steps with a status bit set"] == 0
    if shutil.which("cc") is None:
        pytest.skip("no C compiler: the driver is not built")
    assert c["C driver: steps with a status bit set (OR of bits)"] == 0
    assert "C driver: smc_step loop (-O2)" in report.times
    if shutil.which("valgrind"):
        # The law alone (four psi polynomials, the flat inverse, two sliding variables) is over 100 instructions.
        ir = c["callgrind: instructions per smc_step (200 calls, libm included)"]
        assert 100 < ir < 10_000


def test_bench_batch_api_and_binding_agree():
    report = bench.bench_batch(repeat=1, runs=4, workers=2)
    c = checks(report)
    assert c["runs that failed"] == 0
    assert c["max |theta_final(run_batch) - theta_final(binding)| over the runs"] == 0
    assert c["rows of run_batch that differ from Scenario.run's summaries"] == 0
    assert len(report.times) == 6


def test_cli_bench_refuses_an_unknown_benchmark(capsys):
    assert main(["bench", "--which", "a,z"]) == 2
    assert "unknown benchmark(s) ['z']" in capsys.readouterr().err
