"""The STM32G0 port timestamps frames when its main loop hands them to the core, up to
one receive ring late: PROTOCOL.md 5.3 states that margin, and with it the plate is
still silent within 50 ms of the host falling silent."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PORT = ROOT / "device" / "firmware" / "stm32g0"


def define(path: Path, name: str) -> int:
    """The integer a ``#define name value`` in ``path`` gives."""
    return int(re.search(rf"#define {name} (\d+)u?\b", path.read_text()).group(1))


def test_watchdog_ramp_and_receive_ring_fit_in_50_ms():
    board = PORT / "board.h"
    ring_ms = define(PORT / "uart.c", "RX_SIZE") * 10 / define(board, "BOARD_BAUD") * 1000
    total_ms = define(board, "BOARD_WATCHDOG_MS") + define(board, "BOARD_RAMP_MS") + ring_ms
    assert total_ms <= 50, f"watchdog + ramp + receive ring = {total_ms:.1f} ms > 50 ms"
    section = (ROOT / "device" / "PROTOCOL.md").read_text().split("### 5.3")[1].split("###")[0]
    stated = f"{ring_ms:.1f} ms at {define(board, 'BOARD_BAUD') // 1_000_000} Mbaud"
    assert stated in section, f"PROTOCOL.md 5.3 does not state the {stated} margin"
