import json

import numpy as np
import pytest

import flatstep as fs
from flatstep.cli import main
from flatstep.studies.scenario import PAPER_SCENARIOS

KEYS = {"theta_final", "ia_final", "ib_final", "omega_final", "max_abs_theta_error", "max_abs_rho_error",
        "max_abs_va", "max_abs_vb"}


def test_reproduce_writes_figures_and_summary(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path)]) == 0
    for name in ("fig1.png", "fig2.png", "summary.json"):
        assert (tmp_path / name).stat().st_size > 1000 or name == "summary.json"
    assert (tmp_path / "fig1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary) == {"fig1", "fig2"} and KEYS <= set(summary["fig1"]) and KEYS <= set(summary["fig2"])
    assert summary["fig1"]["max_abs_theta_error"] <= 1e-8
    direct = PAPER_SCENARIOS["fig2"].run().summary()
    assert summary["fig2"]["theta_final"] == pytest.approx(direct["theta_final"], rel=1e-12)
    out = capsys.readouterr().out
    assert "fig1" in out and "fig2" in out and "max_abs_theta_error" in out


def test_simulate_json_matches_the_flags(capsys):
    assert main(["simulate", "--theta2", "0.01", "--load-torque", "1e-6", "--W1", "200", "--W2", "200",
                 "--measurement", "model", "--t-end", "0.05", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert KEYS <= set(s)
    assert abs(s["theta_final"] - 0.01) < 1e-3 and s["theta_final"] != pytest.approx(0.02, abs=1e-3)


def test_simulate_writes_outputs(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "run.png").exists() and (tmp_path / "summary.json").exists()
    data = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    assert data["t"][-1] == pytest.approx(0.06)


def test_infeasible_move_is_refused(capsys):
    assert main(["simulate", "--theta2", "0.05", "--tf", "0.022"]) == 2
    err = capsys.readouterr().err
    assert "refused" in err and "controller singular" in err and "t=0.02" in err


def test_bad_value_names_itself(capsys):
    assert main(["simulate", "--rho1", "-1"]) == 2
    assert "rho1=-1.0" in capsys.readouterr().err
    assert main(["simulate", "--W2", "0"]) == 2
    assert "W2=0.0" in capsys.readouterr().err


def test_unknown_measurement_is_an_argparse_error(capsys):
    assert main(["simulate", "--measurement", "perfect"]) == 2
    assert "invalid choice: 'perfect'" in capsys.readouterr().err


def test_simulate_hold_damping_flag(capsys):
    """--hold-damping: from tf on the rotor rests on the detent, offset by the load over its stiffness."""
    assert main(["simulate", "--hold-damping", "0.7", "--load-torque", "1e-4", "--t-end", "0.1", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    stiffness = 0.05 * 0.4 * 50  # Km rho2 Nr of the paper's motor and move [N m/rad]
    assert s["theta_final"] == pytest.approx(0.02 - 1e-4 / stiffness, abs=1e-6)
    assert main(["simulate", "--hold-damping", "0"]) == 2
    assert "hold_damping=0.0" in capsys.readouterr().err


def test_a_lost_move_exits_3_and_says_when(tmp_path, capsys):
    """The paper's gains on a 20 kHz drive lose the move (docs/drive.md): exit code 3 and a warning."""
    path = tmp_path / "lost.toml"
    path.write_text("[drive]\ncontrol_rate = 20000.0\nv_bus = 24.0\n[controller]\ntype = \"smc\"\nmeasurement = \"model\"\n"
                    "[load]\ntorque = 1e-5\n")
    assert main(["simulate", str(path), "--json"]) == 3
    captured = capsys.readouterr()
    assert json.loads(captured.out)["status"] == "lost"
    assert "lost its move at t = " in captured.err


def test_version_negative_values_and_no_traceback(capsys, monkeypatch):
    import importlib

    import flatstep

    cli_main = importlib.import_module("flatstep.cli.main")  # the module (flatstep.cli.main is the function)

    assert main(["--version"]) == 0 and capsys.readouterr().out.strip() == f"flatstep {flatstep.__version__}"
    assert main(["simulate", "--load-torque", "-1e-5", "--json"]) == 0  # a negative value in scientific notation
    assert json.loads(capsys.readouterr().out)["status"] == "ok"

    def broken(args):
        raise RuntimeError("something unexpected")

    monkeypatch.setattr(cli_main, "cmd_reproduce", broken)
    assert main(["reproduce"]) == 1
    err = capsys.readouterr().err
    assert "internal error: RuntimeError: something unexpected" in err and "--debug" in err
    assert "Traceback" not in err
    assert main(["--debug", "reproduce"]) == 1
    assert "Traceback" in capsys.readouterr().err


def _cpu_seconds(pid: int) -> float:
    """CPU time [s] a process has used, from /proc (Linux)."""
    import os

    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not __import__("os").path.exists("/proc/self/stat"), reason="reads CPU time from /proc")
def test_ctrl_c_stops_a_long_c_run_quickly(tmp_path):
    """SIGINT during a long C run (10 s of 20 kHz control): the run stops within a second, exit code 130."""
    import signal
    import subprocess
    import sys
    import time

    path = tmp_path / "long.toml"
    path.write_text("t_end = 10.0\n[drive]\ncontrol_rate = 20000.0\nsubsteps = 200\n[controller]\n"
                    "measurement = \"model\"\n")
    # SIGINT at its default in the child, so Python installs its Ctrl-C handler even when this test runs in a
    # background job (which starts with SIGINT ignored)
    proc = subprocess.Popen([sys.executable, "-m", "flatstep", "simulate", str(path)], stderr=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # wait until the process has used 2 s of CPU: its imports take under 1 s, so the C run is under way (a fixed
    # sleep is not enough on a loaded machine)
    deadline = time.monotonic() + 60.0
    while _cpu_seconds(proc.pid) < 2.0 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.1)
    assert proc.poll() is None, proc.communicate()
    start = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=20)
    assert proc.returncode == 130 and "interrupted" in err
    assert time.perf_counter() - start < 1.5  # the process's own exit included (the run stops in < 0.5 s, below)


def test_ctrl_c_stops_a_c_run_in_the_main_thread_within_half_a_second():
    """The C loop polls its cancel flag every period: from SIGINT to KeyboardInterrupt in < 0.5 s."""
    import os
    import signal
    import threading
    import time

    scenario = fs.Scenario(loop=fs.DriveLoop(5e-5, substeps=200), measurement="model", t_end=10.0)
    sent = []

    def fire():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.3, fire)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            scenario.run()
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert sent and time.perf_counter() - sent[0] < 0.5
