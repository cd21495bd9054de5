"""The sampled drive loop on the C engine (``sampled_run``) against the Python reference (``flatstep.loop.reference``).

Both loops do the same arithmetic in the same order, except where NumPy and libm round differently (the law's
``arccos``, the observer's matrix product, which NumPy hands to BLAS): their states then differ by about
1e-16 rad. The sensors quantize, so such a difference could move a reading across an encoder count edge, and
from then on the runs would differ by a count (3.8e-4 rad), not by rounding. For that the true angle must fall
within 1e-16 rad of an edge at a sample instant, about one chance in 1e12 per sample. No run here does: every
encoder reading in model mode is bit-identical, and theta agrees to 1e-12 rad over the whole 60 ms run.
Measured with ``run_pair`` below, over the ten runs of ``RUNS``: max |dtheta| 3.5e-18 to 4.1e-16 rad, max
|dia| 5.6e-17 to 1.6e-14 A, max |dv| 1.8e-15 to 5.0e-13 V (the law's voltages differ by an ulp from the first
period on). A count flip would show as a failure of the 1e-12 rad bound, not pass silently.
"""
import numpy as np
import pytest

import flatstep as fs
from flatstep import core
from flatstep.loop.drive import Drive
from flatstep.loop.observers import Observer
from flatstep.loop.sensors import Sensors
from flatstep.model.plant import PlantEffects

TS = 5e-5
DESIGNED = fs.SMCGains(W1=150, W2=3e5, eps1=0.025, eps2=50, xi=0.9, wn=1500)
COUNT = 2 * np.pi / 16384
EXACT = Sensors(encoder_counts=None, current_bits=None)
NOISY = Sensors(current_noise=5e-3, seed=2, current_offset=(2e-3, -1e-3), encoder_offset=0.25)

RUNS = {  # name: (measurement, DriveLoop settings)
    "exact sensors, observer": ("observer", dict(sensors=EXACT, observer=Observer(1500.0))),
    "14-bit, 12-bit, noise, speed observer": ("observer", dict(sensors=NOISY, observer=Observer(1500.0, 0))),
    "14-bit, 12-bit, noise, load observer": ("observer", dict(sensors=NOISY, observer=Observer(1500.0, 1))),
    "14-bit, 12-bit, noise, load-ramp observer": ("observer", dict(sensors=NOISY, observer=Observer(1500.0, 2))),
    "sensors, no observer": ("model", dict(sensors=NOISY)),
    "measurement delay": ("observer", dict(sensors=Sensors(delay=3), observer=Observer(1500.0))),
    "measurement delay, no observer": ("model", dict(sensors=Sensors(delay=8))),
    "compute delay": ("observer", dict(sensors=Sensors(), observer=Observer(1500.0), compute_delay=True)),
    "bus saturation": ("observer", dict(sensors=Sensors(), observer=Observer(1500.0), drive=Drive(v_bus=2.5))),
    "bus only, ideal measurement": ("ideal", dict(drive=Drive(v_bus=2.5))),
}


def run_pair(motor, plan, measurement, options, gains=DESIGNED, effects=None, engines=("c", "python"), **kw):
    """The same run on the C engine and on the Python reference: 60 ms at 20 kHz, perturbed plant, 1e-5 N m.

    ``engines=("c",)`` gives the C run alone (a one-tuple), for the checks that need no reference.
    """
    perturbed = motor.replace(R=1.1 * motor.R, L=0.9 * motor.L, Km=0.9 * motor.Km, J=1.1 * motor.J, B=0.9 * motor.B)
    plant = fs.Plant(perturbed, effects=effects, load=1e-5)
    ctrl = fs.FlatnessSMC(motor, plan, gains, measurement)
    loop = fs.DriveLoop(**{"control_period": TS, "substeps": 4, "drive": Drive(), **options})
    return tuple(fs.simulate(plant, plan, ctrl, loop=loop, engine=engine, **kw) for engine in engines)


@pytest.mark.parametrize("name", RUNS)
def test_c_drive_loop_matches_the_reference(motor, plan, name):
    """Each run of RUNS gives the reference's states, voltages and measurements on the C engine."""
    measurement, options = RUNS[name]
    c, py = run_pair(motor, plan, measurement, options)
    assert c.meta["engine"] == "c" and py.meta["engine"] == "python"
    np.testing.assert_array_equal(c.t, py.t)
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.omega, py.omega, rtol=0, atol=1e-8)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    for key in ("theta", "omega"):
        np.testing.assert_allclose(c.meta["measured"][key], py.meta["measured"][key], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(c.meta["measured"]["ddtheta"], py.meta["measured"]["ddtheta"], rtol=1e-9, atol=1e-6)
    assert c.meta["controller_faults"] == py.meta["controller_faults"] == 0
    assert set(py.meta) <= set(c.meta)
    assert c.summary()["max_abs_theta_error_move"] < 5 * COUNT  # the loop tracks: a check on both engines
    if measurement == "model":  # the controller saw the encoder itself: not one reading may differ
        np.testing.assert_array_equal(c.meta["measured"]["theta"], py.meta["measured"]["theta"])


def test_c_detent_hold_matches_the_reference(motor, plan):
    """The hold from tf on (gains.hold_damping) on both engines, with the observer it is meant for."""
    gains = fs.SMCGains(**{**DESIGNED.as_dict(), "hold_damping": 0.7})
    c, py = run_pair(motor, plan, "observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)), gains=gains)
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    plain, = run_pair(motor, plan, "observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)), engines=("c",))
    rest = c.t >= plan.tf
    assert np.array_equal(c.va[~rest], plain.va[~rest]) and not np.array_equal(c.va[rest], plain.va[rest])
    i_star = fs.FlatnessSMC(motor, plan, gains).hold_currents(0.0)
    np.testing.assert_allclose([c.ia[-1], c.ib[-1]], i_star, atol=0.02)  # the currents sit on the detent


def test_the_saturation_runs_use_the_bus(motor, plan):
    """Without this the bus-saturation parity above would not test the saturation."""
    for name in ("bus saturation", "bus only, ideal measurement"):
        c, = run_pair(motor, plan, *RUNS[name], t_end=0.045, engines=("c",))
        peak = np.maximum(np.abs(c.va), np.abs(c.vb))
        assert np.sum(np.isclose(peak, 2.5, rtol=0, atol=1e-12)) > 10 and peak.max() <= 2.5 + 1e-12


def test_delays_shift_what_the_c_loop_sees(motor, plan):
    """A measurement delay shifts the encoder readings by its periods; a compute delay holds the start's voltages."""
    c, = run_pair(motor, plan, "model", dict(sensors=Sensors(delay=8)), t_end=0.04, engines=("c",))
    enc = Sensors(delay=8).read_angle(c.theta)
    np.testing.assert_array_equal(c.meta["measured"]["theta"][8:], enc[:-8])
    assert np.all(c.meta["measured"]["theta"][:8] == enc[0])
    c, = run_pair(motor, plan, "observer", dict(sensors=Sensors(), observer=Observer(1500.0), compute_delay=True),
                  t_end=0.04, engines=("c",))
    assert c.va[0] == motor.R * c.ia[0] and c.vb[0] == 0.0  # the start equilibrium until the first command lands


def test_controller_faults_are_counted_alike(motor, plan):
    """No current at all: rho = 0 is outside the law's domain, so both loops de-energise every period."""
    c, py = run_pair(motor, plan, "model", dict(sensors=Sensors()), x0=[0.0, 0.0, 0.0, 0.0], t_end=0.04)
    assert c.meta["controller_faults"] == py.meta["controller_faults"] == c.t.size
    assert c.meta["first_fault_time"] == py.meta["first_fault_time"] == 0.0
    assert np.all(c.va == 0) and np.all(c.theta == py.theta)
    assert "rho" in c.meta["controller_status"]


@pytest.mark.parametrize("options", [
    dict(sensors=Sensors(), observer=Observer()),
    dict(compute_delay=True),
    dict(sensors=Sensors(delay=8), observer=Observer()),
])
def test_default_engine_is_c(motor, plan, options):
    """A drive loop with sensors, an observer or a delay runs on the C engine by default."""
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "observer" if "observer" in options else "ideal")
    r = fs.simulate(motor, plan, ctrl, loop=fs.DriveLoop(TS, **options), t_end=0.04)
    assert r.meta["engine"] == "c" and r.meta["control_period"] == TS


def test_c_engine_runs_plant_effects_like_the_reference(motor, plan):
    """Detent (2nd harmonic), Coulomb friction and iron loss on the plant, in the loop the C engine runs."""
    effects = PlantEffects(detent_torque=2e-4, detent_harmonic=2, coulomb_torque=1e-4, coulomb_speed=0.5,
                           magnetizing_resistance=50.0)
    c, py = run_pair(motor, plan, "observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)), effects=effects)
    plain, = run_pair(motor, plan, "observer", dict(sensors=NOISY, observer=Observer(1500.0, 2)), engines=("c",))
    assert c.meta["engine"] == "c" and c.meta["plant"]["effects"] == effects.as_dict()
    np.testing.assert_allclose(c.theta, py.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.ia, c.ib], [py.ia, py.ib], rtol=0, atol=1e-12)
    np.testing.assert_allclose([c.va, c.vb], [py.va, py.vb], rtol=0, atol=1e-9)
    assert np.max(np.abs(c.theta - plain.theta)) > 1e-6  # the effects act on the C plant


def test_c_engine_refuses_what_it_does_not_model(motor, plan):
    """The C engine refuses a delay of over 8 periods, naming it; the Python engine runs it."""
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "observer")
    loop = fs.DriveLoop(TS, sensors=Sensors(delay=9), observer=Observer())
    with pytest.raises(ValueError, match=r"sensors.delay=9 periods \(the C loop holds at most 8\)"):
        fs.simulate(motor, plan, ctrl, loop=loop, engine="c")
    assert fs.simulate(motor, plan, ctrl, loop=loop, engine="python", t_end=0.04).meta["engine"] == "python"


def test_run_sampled_checks_the_noise_shape(motor, plan):
    """A noise array of the wrong shape is refused, naming its shape and the one expected."""
    ctrl = fs.FlatnessSMC(motor, plan, DESIGNED, "model")
    with pytest.raises(ValueError, match=r"noise has shape \(10, 2\); expected \(11, 2\)"):
        core.run_sampled(ctrl, motor, 0.0, plan.x0(motor.Nr), 10, Ts=TS, substeps=4, sensors=Sensors(),
                          noise=np.zeros((10, 2)))
