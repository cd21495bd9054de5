"""Write the seeds and regression inputs of the time_optimal, traj, flat, dq_smc, time_optimal_dq and sampled targets.

Each input follows its harness's layout (fuzz/fuzz_<target>.c) in the encoding of fuzz/decode.h: a value is a tag
byte and 8 payload bytes, tag 0 the raw IEEE bits, tag 3 with a zero payload the harness's nominal value.
Run from the repository root: ``python3 fuzz/make_seeds.py``.
"""

import struct
from pathlib import Path

ROOT = Path(__file__).resolve().parent


def val(x: float) -> bytes:
    """Return the encoding of the exact value x."""
    return b"\x00" + struct.pack("<d", x)


def nom() -> bytes:
    """Return the encoding of the harness's nominal value."""
    return b"\x03" + bytes(8)


def u32(x: int) -> bytes:
    """Return a 32-bit mask or count."""
    return struct.pack("<I", x)


def write(kind: str, target: str, name: str, data: bytes) -> None:
    """Write one input to fuzz/<kind>/<target>/<name>."""
    path = ROOT / kind / target / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def time_optimal() -> None:
    """Seeds of fuzz_time_optimal: head, mask, distance, widths, shortfall, motor, limits, table."""
    for d in (0.1, 1.0, 5.0, 20.0, -2.0):
        write("seeds", "time_optimal", f"move-{d:g}", bytes([2]) + u32(0) + val(d))
    write("seeds", "time_optimal", "bus-12V-margins", bytes([8]) + u32(2) + val(1.0) + val(12.0))
    write("seeds", "time_optimal", "caps", bytes([0]) + u32(0x380) + val(3.0) + val(400.0) + val(2e4) + val(1e7))
    write("seeds", "time_optimal", "short-workspace", bytes([4]) + u32(0) + val(1.0) + b"\x00")
    write("seeds", "time_optimal", "three-widths", bytes([1]) + u32(0) + val(1.0) + b"\x03" + nom() * 3)
    write("seeds", "time_optimal", "motor", bytes([0]) + u32(1) + val(1.0) + nom() * 5 + b"\x32")
    # moves of 1e-6 .. 1.5e-5 rad once wrote past the workspace (the box filter's running sum)
    for d in (1e-5, 3e-6, 1.2e-5, 1.5e-5, -1e-5, 2e-5, 1e-7, 1e-9):
        write("regressions", "time_optimal", f"tiny-move-{d:g}", bytes([2 | 8]) + u32(0) + val(d))
    for w in (1e300, 1e-300):
        for d in (1.0, 1e-5):
            data = bytes([1]) + u32(0) + val(d) + b"\x01" + val(w)
            write("regressions", "time_optimal", f"width-{w:g}-move-{d:g}", data)


def traj_table(head: int, breaks: list[float], times: list[float]) -> bytes:
    """Return a fuzz_traj input: the breaks, nominal rows, then the times (each with the guess 0)."""
    n = len(breaks) - 1
    rows = nom() * (2 * n * 11)
    return bytes([head]) + b"".join(val(b) for b in breaks) + rows + bytes([len(times)]) + b"".join(
        val(t) + b"\x00\x00" for t in times
    )


def traj() -> None:
    """Seeds of fuzz_traj: head (segments, missing arrays, plan_flag), breaks, rows, times and guesses."""
    write("seeds", "traj", "nominal-4", bytes([4 | 32]))
    write("seeds", "traj", "nominal-8", bytes([7 | 64 | 32]))
    write("seeds", "traj", "one-segment", bytes([1]))
    write("seeds", "traj", "no-segment", bytes([0]))
    write("seeds", "traj", "no-theta", bytes([2 | 8]))
    write("seeds", "traj", "no-breaks", bytes([2 | 16]))
    nan, inf = float("nan"), float("inf")
    ends = [0.0, 1.0, 1.00001, 2.0, 1.000005, -1.0, 3.0, nan, inf, -inf, 0.9999999999999999]
    # a tiny segment between two long ones: the segment lookup and the scaling by 1 / h
    write("regressions", "traj", "tiny-segment", traj_table(3 | 32, [0.0, 1.0, 1.00001, 2.0], ends))
    write("regressions", "traj", "segment-1e-77", traj_table(2 | 32, [0.0, 1e-77, 1.0], [5e-78, 1e-77, 0.5]))
    write("regressions", "traj", "segment-1e-300", traj_table(2, [0.0, 1e-300, 1.0], [5e-301, 0.5]))
    write("regressions", "traj", "equal-breaks", traj_table(3, [0.0, 1.0, 1.0, 2.0], [1.0, 1.5]))
    write("regressions", "traj", "huge-breaks", traj_table(2 | 32, [-1e300, 0.0, 1e300], [-5e299, 1.0, 1e300]))


def flat() -> None:
    """Seeds of fuzz_flat: head (samples), mask (hostile groups), motor, plan, load, times, states, arguments."""
    write("seeds", "flat", "nominal", bytes([16]) + u32(0))
    for bit, name in enumerate(("motor", "plan", "load", "times", "arguments", "states")):
        write("seeds", "flat", f"near-{name}", bytes([16]) + u32(1 << bit))
    plan = [val(0.0), val(0.02), nom(), nom(), val(0.03), val(0.03)]  # tf = t0: not a plan, held at the start
    write("seeds", "flat", "empty-span", bytes([16]) + u32(2) + b"".join(plan))
    plan = [val(0.0), val(0.02), val(0.0), nom(), nom(), nom()]  # rho1 = 0: outside the maps' domain
    write("seeds", "flat", "zero-current", bytes([16]) + u32(2) + b"".join(plan))
    states = [val(0.0), val(0.0), nom(), nom(), nom(), nom()]  # ia = ib = 0
    write("seeds", "flat", "zero-state", bytes([1]) + u32(32) + b"".join(states))


def dq_smc() -> None:
    """Seeds of fuzz_dq_smc: head (measurement, hostile groups), options, the groups, steps."""
    write("seeds", "dq_smc", "ideal", bytes([0, 0]))
    write("seeds", "dq_smc", "model", bytes([1, 0]))
    write("seeds", "dq_smc", "d-current", bytes([8, 0]))
    write("seeds", "dq_smc", "torques", bytes([32, 0]))
    write("seeds", "dq_smc", "integral", bytes([64, 0]))
    write("seeds", "dq_smc", "adaptation", bytes([128, 0]))
    write("seeds", "dq_smc", "integral-adaptation-model", bytes([1 | 64 | 128, 0]))
    write("seeds", "dq_smc", "v-limit", bytes([0, 1]) + val(1e-3))


def time_optimal_dq() -> None:
    """Seeds of fuzz_time_optimal_dq: head, mask, distance, shortfall, motor, limits."""
    for d in (0.3, 1.0, 5.0, -2.0):
        write("seeds", "time_optimal_dq", f"move-{d:g}", bytes([0, 0]) + val(d))
    write("seeds", "time_optimal_dq", "bus-12V", bytes([0, 2]) + val(1.0) + val(12.0))
    write("seeds", "time_optimal_dq", "speed-cap", bytes([0, 16]) + val(5.0) + val(40.0))
    write("seeds", "time_optimal_dq", "short-workspace", bytes([4, 0]) + val(1.0) + b"\x00")
    write("seeds", "time_optimal_dq", "motor", bytes([0, 1]) + val(1.0) + nom() * 5 + b"\x32")


def sampled() -> None:
    """Seeds of fuzz_sampled with its options byte: head (law), mask, a faster plan, periods, options, Bf."""
    # mask bits: 6 sensors, 8 observer, 15 the plan (0 .. 0.3 rad over 20 ms: the encoder's edges come within a period)
    plan = val(0.0) + val(0.3) + nom() * 4
    for law, name in enumerate(("smc", "microstep", "cascade", "exact")):
        write("seeds", "sampled", f"{name}-observed-edge-ramp", bytes([law]) + u32(0x8140) + plan + bytes([250, 3]))
    write("seeds", "sampled", "smc-observed-edge", bytes([0]) + u32(0x8140) + plan + bytes([250, 1]))
    ramp_near = bytes([2]) + u32(0x8140) + plan + bytes([250, 6]) + nom() * 4  # Bf decoded: 4 values near flatstep's
    write("seeds", "sampled", "cascade-observed-ramp-near", ramp_near)
    write("seeds", "sampled", "smc-sensed-edge", bytes([0]) + u32(0x8040) + plan + bytes([250, 1]))


if __name__ == "__main__":
    time_optimal()
    traj()
    flat()
    dq_smc()
    time_optimal_dq()
    sampled()
