#!/usr/bin/env python3
"""Floating-point operations a program executes, counted per instruction: callgrind's execution count
of every instruction of the program's own binary (valgrind --tool=callgrind --dump-instr=yes) times
the double-precision operations the instruction does (objdump's disassembly): add, sub, mul, div,
sqrt; scalar (..sd) 1, packed (..pd) 2 / 4 / 8 on xmm / ymm / zmm, a fused multiply-add 2 per lane
(none: the build has -ffp-contract=off). Moves, sign flips (xor), abs (and), compares, min/max and
conversions are not FLOPs. Valgrind runs no AVX-512, so the lane ABA's AVX2 clone is the one counted;
the operations are the same on every path (docs/performance.md, "100-DOF arms in real time").

Usage: count_flops.py BINARY [ARGS...]   (prints the FLOP count of the run's own binary)
"""
import os
import re
import subprocess
import sys
import tempfile

OP = re.compile(r"^v?(add|sub|mul|div|sqrt)(sd|pd)$")
FMA = re.compile(r"^vf(n?)m(add|sub)(132|213|231)(sd|pd)$")


def flops_of(mnemonic, operands):
    width = 8 if "zmm" in operands else 4 if "ymm" in operands else 2
    m = OP.match(mnemonic)
    if m:
        return 1 if m.group(2) == "sd" else width
    m = FMA.match(mnemonic)
    if m:
        return 2 if m.group(4) == "sd" else 2 * width
    return 0


def disassemble(binary):
    """address -> flops of every FP arithmetic instruction in the binary's text."""
    out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", binary], capture_output=True, text=True,
                         check=True).stdout
    table = {}
    for line in out.splitlines():
        m = re.match(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
        if not m:
            continue
        f = flops_of(m.group(2), m.group(3))
        if f:
            table[int(m.group(1), 16)] = f
    return table


def main():
    binary = os.path.realpath(sys.argv[1])
    table = disassemble(binary)
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "cg.out")
        subprocess.run(["valgrind", "--tool=callgrind", "--dump-instr=yes", "--compress-pos=no",
                        "--compress-strings=no", "--callgrind-out-file=" + out] + sys.argv[1:], check=True,
                       stderr=subprocess.DEVNULL)
        total = 0
        ours = False
        skip_next = False
        with open(out) as f:
            for line in f:
                if line.startswith("ob="):
                    ours = os.path.realpath(line[3:].strip()) == binary
                    continue
                if line.startswith("calls="):
                    skip_next = True  # the next cost line is the call's inclusive cost
                    continue
                if not line.startswith("0x"):
                    continue
                if skip_next:
                    skip_next = False
                    continue
                if not ours:
                    continue
                parts = line.split()
                addr = int(parts[0], 16)  # callgrind writes addresses relative to the object, as objdump
                f_ = table.get(addr)
                if f_:
                    total += f_ * int(parts[-1])
    print(total)


if __name__ == "__main__":
    main()
