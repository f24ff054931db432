"""Instructions and estimated cycles per sample of the STM32G0 build, counted by running
its own sample interrupt in an instruction-set emulator (unicorn, in the ``test`` extra).

The ELF that ``make stm32g0`` links is loaded as it lies in flash and RAM; the setup that
``main()`` does is replayed by calling the firmware's own functions (``fw_init``,
``sample_clock_start``); the host's frames (a Hello, then a 50-sample Block and a
Heartbeat every 50 ticks, as ``test/tick_bench.c``) go in through ``fw_receive`` as the
main loop hands them over; and ``tim6_irq``, the whole per-sample path (``fw_tick``, the
DAC scaling and store, the watchdog kick), runs once per tick. The peripherals are plain
memory: the DAC's register keeps what the interrupt stored there, which is checked
against the commanded samples. Cycles: :func:`isr_cycles.cycles`'s Cortex-M0+ timings
(1 per instruction, loads and stores 2, taken branches 2, BL/BX 3, PUSH/POP/LDM/STM
1 + registers, POP into pc 3 + registers) plus :data:`ENTRY_EXIT_CYCLES` for the
exception's entry and return; flash wait states are not counted.

    .venv/bin/python device/firmware/isr_unicorn.py      # prints the figures
"""

from __future__ import annotations

import importlib.util
import struct
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from frictex.device.firmware.build import BUILD, FIRMWARE, make, require
from frictex.device.link import protocol as p

#: Cortex-M0+ exception entry (its stated 15-cycle interrupt latency: eight registers
#: stacked, the vector fetched) and return (eight unstacked and the branch), cycles
ENTRY_EXIT_CYCLES = 15 + 15
#: the STM32G0 port's system clock (Hz) and sample rate (Hz): stm32g0/board.h
SYSCLK_HZ = 64_000_000
RATE_HZ = 10_000
#: cycles one sample has: 6,400 at 64 MHz and 10 kHz
BUDGET_CYCLES = SYSCLK_HZ // RATE_HZ
DAC_DHR12RD = 0x40007420
_RETURN = 0x0801FF00  # a halfword in mapped flash past the code: where each call returns
_SCRATCH = 0x20008000  # RAM past the build's 8 KiB budget: frames handed to fw_receive
_CHANNELS, _LIMIT, _BLOCK = 2, 16384, 50


@dataclass(frozen=True)
class IsrCost:
    """Per-sample cost of ``tim6_irq``, over the ticks of steady playing."""

    ticks: int               #: interrupts counted
    instructions_mean: float
    instructions_max: int
    cycles_mean: float       #: estimated, entry and return included
    cycles_max: int

    def summary(self) -> str:
        return (f"tim6_irq (STM32G0 build, Cortex-M0+): {self.instructions_mean:.1f} "
                f"instructions per sample (at most {self.instructions_max}), about "
                f"{self.cycles_mean:.0f} cycles with entry and return (at most "
                f"{self.cycles_max}) of the {BUDGET_CYCLES} a {RATE_HZ // 1000} kHz sample "
                f"has at {SYSCLK_HZ // 1_000_000} MHz: "
                f"{100 * self.cycles_max / BUDGET_CYCLES:.1f} % at most, "
                f"over {self.ticks} ticks")


def _isr_cycles():
    spec = importlib.util.spec_from_file_location("isr_cycles", FIRMWARE / "test" / "isr_cycles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _symbols(elf: Path) -> dict[str, tuple[int, int]]:
    """name -> (address, size); of names defined twice (``device``), the larger."""
    out = subprocess.run(["arm-none-eabi-nm", "-S", str(elf)], capture_output=True, text=True,
                         check=True).stdout
    found: dict[str, tuple[int, int]] = {}
    for line in out.splitlines():
        parts = line.split()
        size = int(parts[1], 16) if len(parts) == 4 else 0
        if size >= found.get(parts[-1], (0, 0))[1]:
            found[parts[-1]] = (int(parts[0], 16), size)
    return found


def _segments(elf: Path):
    """(address, bytes, size in memory) of each loadable segment, at its run address."""
    data = elf.read_bytes()
    phoff, = struct.unpack_from("<I", data, 28)
    phentsize, phnum = struct.unpack_from("<HH", data, 42)
    for i in range(phnum):
        kind, off, vaddr, _, filesz, memsz = struct.unpack_from("<6I", data, phoff + i * phentsize)
        if kind == 1:  # PT_LOAD
            yield vaddr, data[off:off + filesz], memsz


class _Board:
    """The STM32G0 build in unicorn: memory, the firmware's functions callable."""

    def __init__(self, elf: Path):
        from unicorn import UC_ARCH_ARM, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
        from unicorn.arm_const import UC_CPU_ARM_CORTEX_M0
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M0)
        for base, size in ((0x08000000, 0x20000), (0x20000000, 0x10000),
                           (0x40000000, 0x30000), (0x50000000, 0x1000), (0xE000E000, 0x1000)):
            self.uc.mem_map(base, size)
        for addr, blob, _ in _segments(elf):
            self.uc.mem_write(addr, blob)
        self.uc.mem_write(_RETURN, b"\x00\xbf")  # nop
        self.sym = _symbols(elf)
        self.stack_top = self.sym["_estack"][0]

    def call(self, name: str, *args: int, hook=None) -> None:
        from unicorn.arm_const import UC_ARM_REG_LR, UC_ARM_REG_R0, UC_ARM_REG_SP
        for i, value in enumerate(args):
            self.uc.reg_write(UC_ARM_REG_R0 + i, value)
        self.uc.reg_write(UC_ARM_REG_SP, self.stack_top)
        self.uc.reg_write(UC_ARM_REG_LR, _RETURN | 1)
        self.uc.emu_start(self.sym[name][0] | 1, _RETURN, count=5_000_000)

    def receive(self, frames: bytes, tick: int) -> None:
        self.uc.mem_write(_SCRATCH, frames)
        self.call("fw_receive", self.sym["device"][0], _SCRATCH, len(frames), tick)

    def dac(self) -> int:
        return struct.unpack("<I", self.uc.mem_read(DAC_DHR12RD, 4))[0]


def commanded(ticks: int) -> np.ndarray:
    """The amplitudes streamed (counts, shape (ticks, 2)): two sawtooths that never reach
    a zero DAC code (a count is 1/4 of a code)."""
    n = np.arange(ticks)
    return (8 + np.stack([n * 37, n * 101], 1) % (_LIMIT - 8)).astype(np.uint16)


def dac_word(amp: np.ndarray) -> np.ndarray:
    """What the interrupt stores to DAC_DHR12RD for setpoints ``amp`` (stm32g0/sample_clock.c)."""
    scale = (4095 << 16) // _LIMIT
    codes = (amp.astype(np.int64) * scale) >> 16
    return codes[:, 0] | (codes[:, 1] << 16)


def measure(ticks: int = 2000, prefill: int = 100) -> tuple[IsrCost, np.ndarray]:
    """Run ``tim6_irq`` ``ticks`` times on a stream kept ``prefill`` samples ahead; returns
    the cost over the ticks after the first ``2 * prefill`` and the DAC word after each
    tick."""
    from unicorn import UC_HOOK_CODE
    make("stm32g0")
    require("arm-none-eabi-nm", "arm-none-eabi-objdump")
    elf = BUILD / "stm32g0" / "frictex-fw.elf"
    model = _isr_cycles()
    insns, _ = model.disassembly(str(elf), "arm-none-eabi-objdump")
    board = _Board(elf)
    device = board.sym["device"][0]
    board.call("fw_init", device, board.sym["config"][0], board.sym["hal"][0], 0)
    board.call("sample_clock_start", device)
    amps = commanded(ticks + prefill + _BLOCK)
    seq = 0

    def send(*messages, tick):
        nonlocal seq
        board.receive(b"".join(p.encode(m, seq + k) for k, m in enumerate(messages)), tick)
        seq += len(messages)

    send(p.Hello(prefill), tick=0)
    pcs: list[int] = []
    counts, cycles, words = [], [], []
    for t in range(ticks):
        if t % _BLOCK == 0:
            send(p.Block(t, amps[t:t + _BLOCK]), p.Heartbeat(t), tick=t)
        board.call("fw_poll", device)
        pcs.clear()
        hook = board.uc.hook_add(UC_HOOK_CODE, lambda uc, addr, size, _: pcs.append(addr))
        board.call("tim6_irq")
        board.uc.hook_del(hook)
        pcs.pop()  # the nop it returned to
        total = 0
        for i, pc in enumerate(pcs):
            size, mnemonic, operands = insns[pc]
            nxt = pcs[i + 1] if i + 1 < len(pcs) else None  # the return: counted as taken
            total += model.cycles(mnemonic, operands, nxt != pc + size)
        counts.append(len(pcs))
        cycles.append(total + ENTRY_EXIT_CYCLES)
        words.append(board.dac())
    steady = slice(2 * prefill, None)
    cost = IsrCost(len(counts[steady]), float(np.mean(counts[steady])), int(max(counts[steady])),
                   float(np.mean(cycles[steady])), int(max(cycles[steady])))
    return cost, np.array(words, np.int64)


if __name__ == "__main__":
    print(measure()[0].summary())
