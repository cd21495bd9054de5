"""embedded/m4_cycles.awk: the Cortex-M4F cycle bounds of an instruction mix (ARM's Cortex-M4 TRM timings)."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "embedded" / "m4_cycles.awk"

# A disassembly as arm-none-eabi-objdump -d prints it, and for each instruction its cycles (low, high).
LISTING = [
    ("100", "ed2d 8b04", "vpush", "{d8-d9}", (5, 5)),           # 1 + N singles, a double is two
    ("104", "b530", "push", "{r4, r5, lr}", (4, 4)),            # 1 + N
    ("106", "ee87 7a27", "vdiv.f32", "s14, s14, s15", (14, 14)),
    ("10a", "ee07 7a27", "vmla.f32", "s14, s14, s15", (3, 3)),
    ("10e", "ed93 7a00", "vldr", "s14, [r3]", (1, 2)),
    ("112", "ee10 0a10", "vmov", "r0, s0", (1, 2)),             # between core and FPU registers
    ("116", "eeb0 0a49", "vmov.f32", "s0, s18", (1, 1)),
    ("11a", "6803", "ldr", "r3, [r0, #0]", (1, 2)),             # 1 when pipelined behind another load
    ("11c", "bf88", "it", "hi", (0, 1)),
    ("11e", "3301", "adds", "r3, #1", (1, 1)),
    ("120", "d1f0", "bne.n", "104 <f+0x4>", (1, 4)),            # not taken, or taken with a refill of 1-3
    ("122", "f7ff ffed", "bl", "100 <g>", (2, 4)),
    ("126", "fb93 f3f2", "sdiv", "r3, r3, r2", (2, 12)),
    ("12a", "ecbd 8b04", "vpop", "{d8-d9}", (5, 5)),
    ("12e", "bd30", "pop", "{r4, r5, pc}", (5, 7)),             # 1 + N, plus the refill when it loads pc
]


@pytest.mark.skipif(shutil.which("awk") is None, reason="needs awk")
def test_cycle_bounds_of_an_instruction_mix(tmp_path):
    dump = "\n".join(["", "f.elf:     file format elf32-littlearm", "", "00000100 <f>:"]
                     + [f"     {a}:\t{code:<10}\t{op}\t{args}" for a, code, op, args, _ in LISTING]) + "\n"
    (tmp_path / "dump.txt").write_text(dump)
    # call 1 runs each instruction 3 times, call 2 once; an address outside the image is reported
    counts = [f"1 {int(a, 16):08x} 3" for a, *_ in LISTING] + [f"2 {int(a, 16):08x} 1" for a, *_ in LISTING]
    (tmp_path / "pcs.txt").write_text("\n".join(counts + ["2 0000ffff 7"]) + "\n")
    out = subprocess.run(["awk", "-f", str(SCRIPT), "dump.txt", "pcs.txt"], cwd=tmp_path, capture_output=True,
                         text=True, check=True).stdout.splitlines()
    low, high, n = sum(c[4][0] for c in LISTING), sum(c[4][1] for c in LISTING), len(LISTING)
    assert out[0].startswith(f"   call 1: {3 * n} instructions, {3 * low} to {3 * high} cycles")
    assert "; 3 divisions and square roots)" in out[0]
    assert out[1].startswith(f"   call 2: {n} instructions, {low} to {high} cycles")
    assert out[1].endswith(", 7 not in the image")
