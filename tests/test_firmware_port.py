"""The Cortex-M0+ port (STM32G071, arm-none-eabi-gcc -Os) fits its budget: 32 KiB of flash
and 8 KiB of RAM; and the per-sample work of the sample interrupt, counted."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from frictex.device.firmware.build import FirmwareBuildError, make


def _make(*targets):
    try:
        return make(*targets)
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


def test_the_stm32g0_build_fits_32_kib_of_flash_and_8_kib_of_ram():
    out = _make("stm32g0")
    sections = {m.group(1): int(m.group(2))
                for m in re.finditer(r"^\.(\w+)\s+(\d+)\s+\d+$", out, re.M)}
    flash = sections["isr_vector"] + sections["text"] + sections["data"]
    ram = sections["data"] + sections["bss"] + sections["stack"]
    assert flash <= 32 * 1024 and ram <= 8 * 1024
    assert sections["stack"] >= 768  # room for the worst call chain plus both interrupts
    assert f"flash {flash} of 32768 bytes, RAM {ram} of 8192 bytes" in out


def test_the_readme_states_the_stm32g0_sizes_of_its_compiler():
    """device/firmware/README.md's measured flash and RAM are this build's, with the
    compiler version it names (another version gives other sizes: skipped)."""
    readme = (Path(__file__).parents[1] / "device/firmware/README.md").read_text()
    stated = re.search(r"Measured \(`make stm32g0`, arm-none-eabi-gcc ([\d.]+) `-Os`\): "
                       r"flash (\d+) bytes of 32 KiB;\s+RAM (\d+) bytes", readme)
    assert stated, "README: the STM32G0 sizes sentence is missing"
    version = subprocess.run(["arm-none-eabi-gcc", "-dumpfullversion"], capture_output=True,
                             text=True).stdout.strip() if shutil.which("arm-none-eabi-gcc") else ""
    if not (version + ".").startswith(stated.group(1) + "."):  # "12.2" names 12.2.1 too
        pytest.skip(f"arm-none-eabi-gcc {version or 'absent'}; the README measured "
                    f"{stated.group(1)}")
    out = _make("stm32g0")
    assert (f"flash {stated.group(2)} of 32768 bytes, RAM {stated.group(3)} of 8192 bytes"
            in out)


def test_the_per_sample_work_is_a_small_fraction_of_a_10_khz_tick_at_48_mhz():
    """fw_tick, the sample interrupt's work, counted by callgrind on the host build while
    the core plays two channels steadily: about 80 instructions per tick (the Thumb-1
    build executes about 150, ~240 cycles, see README); a 48 MHz core has 4800 cycles
    per 10 kHz tick."""
    out = _make("isr-cost")
    m = re.search(r"fw_tick, host build: ([\d,]+) instructions for 100000 ticks", out)
    per_tick = int(m.group(1).replace(",", "")) / 100_000
    assert 20 < per_tick < 300
