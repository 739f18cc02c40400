#!/usr/bin/env python3
"""Cycle estimate of a Cortex-M4 run from QEMU's execution trace (toolchain/benchmarks.sh).

Usage: cortex_m_cycles.py BINARY TRACE_0 TRACE_N N
The traces come from `qemu-arm -singlestep -d exec,nochain` (one line per executed instruction):
TRACE_0 with 0 samples, TRACE_N with N. Each executed instruction is classed by its mnemonic
(arm-none-eabi-objdump) and costed with the Cortex-M4 timings (ARM DDI 0439B, table 3-1): 1 cycle
for data processing and multiplies (UMULL, UMLAL included), 2 for a load (1 when it follows another
load, counted as 2 here), 1 for a store, 1 + N for LDM/STM/PUSH/POP of N registers, a branch 1 plus
the pipeline refill of 1..3 when taken (taken: the next instruction in the trace is not the next
in memory; refill counted as 2), 14 for a division. Prints instructions and cycles per sample.
"""
import collections
import re
import subprocess
import sys

binary, trace0, trace_n, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
code = {}  # address -> (mnemonic, operands, size)
dump = subprocess.run(["arm-none-eabi-objdump", "-d", binary], capture_output=True, text=True, check=True).stdout
for line in dump.splitlines():
    m = re.match(r"\s+([0-9a-f]+):\s+([0-9a-f]{4})(?: ([0-9a-f]{4}))?\s+(\S+)\s*(.*)", line)
    if m:
        code[int(m.group(1), 16)] = (m.group(4), m.group(5), 4 if m.group(3) else 2)


def cost(mnemonic, operands, taken):
    op = mnemonic.split(".")[0]
    regs = operands.count(",") + 1 if "{" in operands else 0
    if op in ("push", "pop", "ldm", "ldmia", "ldmdb", "stm", "stmia", "stmdb", "vpush", "vpop", "vldmia", "vstmia"):
        return 1 + max(regs, 1) + (2 if "pc" in operands else 0)
    if op.startswith(("ldr", "vldr")):
        return 2 + (2 if operands.startswith("pc") else 0)
    if op.startswith(("str", "vstr")):
        return 1
    if op in ("udiv", "sdiv"):
        return 14
    if op.startswith(("b", "cb", "tb")) and op not in ("bic", "bics", "bfi", "bfc"):
        return 1 + (2 if taken else 0)
    return 1


def run(trace):
    pcs = [int(m.group(1), 16) for m in re.finditer(r"\[[0-9a-f]+/([0-9a-f]+)/", open(trace).read())]
    counts = collections.Counter()
    for here, after in zip(pcs, pcs[1:] + [None]):
        counts[(here, after)] += 1
    cycles = 0
    for (here, after), k in counts.items():
        mnemonic, operands, size = code.get(here, ("?", "", 2))
        cycles += k * cost(mnemonic, operands, after is not None and after != here + size)
    return len(pcs), cycles


i0, c0 = run(trace0)
i_n, c_n = run(trace_n)
print(f"{(i_n - i0) / n:.0f} instructions and {(c_n - c0) / n:.0f} cycles per sample")
