"""Instructions and estimated Cortex-M0+ cycles per call of one function, from a qemu trace.

Usage: isr_cycles.py ELF TRACE FUNCTION [OBJDUMP]. TRACE is the log of
``qemu-arm -singlestep -d exec,nochain`` (one line per executed instruction). Cycles
use the Cortex-M0+ timings (ARM DDI 0484C, table 3-1): 1 per instruction, loads and
stores 2, taken branches 2, BL 3, PUSH/POP/LDM/STM 1 + registers (POP into pc 3 +
registers); flash wait states, hidden by the prefetch buffer on straight-line code,
are not counted.
"""

import re
import subprocess
import sys


def disassembly(elf, objdump):
    out = subprocess.run([objdump, "-d", elf], capture_output=True, text=True, check=True).stdout
    insns, funcs, current = {}, {}, None
    for line in out.splitlines():
        head = re.match(r"^([0-9a-f]+) <(.+)>:$", line)
        if head:
            current = head.group(2)
            funcs[current] = [int(head.group(1), 16), int(head.group(1), 16)]
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+((?:[0-9a-f]{4} ?)+)\s+(\S+)\s*(.*)$", line)
        if m and current:
            pc, size = int(m.group(1), 16), len(m.group(2).split()) * 2
            insns[pc] = (size, m.group(3), m.group(4))
            funcs[current][1] = pc + size
    return insns, funcs


def cycles(mnemonic, operands, taken):
    m = mnemonic.split(".")[0]
    regs = operands.count(",") + 1 if "{" in operands else 0
    if m in ("push", "stmia", "stm", "ldmia", "ldm"):
        return 1 + regs
    if m == "pop":
        return 3 + regs if "pc" in operands else 1 + regs
    if m.startswith(("ldr", "str")):
        return 2
    if m in ("bl", "blx", "bx"):
        return 3
    if m.startswith("b") and m not in ("bic", "bics"):
        return 2 if taken else 1
    return 1


def main(elf, trace, function, objdump="arm-none-eabi-objdump"):
    insns, funcs = disassembly(elf, objdump)
    lo, hi = funcs[function]
    pcs = [int(m.group(1), 16) for m in
           (re.search(r"/([0-9a-f]{8})/", line) for line in open(trace)) if m]
    calls = n = total = 0
    for i, pc in enumerate(pcs):
        if not lo <= pc < hi:
            continue
        calls += pc == lo
        size, mnemonic, operands = insns[pc]
        nxt = pcs[i + 1] if i + 1 < len(pcs) else pc + size
        c = cycles(mnemonic, operands, nxt != pc + size)
        n += 1
        total += c
    print(f"{function}: {calls} calls, {n / calls:.1f} instructions and about "
          f"{total / calls:.0f} cycles per call (callees not included)")


if __name__ == "__main__":
    main(*sys.argv[1:])
