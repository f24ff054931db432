/* What every Cortex-M port shares: the reset handler (reset.c) and the interrupt mask
 * that guards the device core (fw_hal's lock and unlock). Each port defines fault(),
 * which the reset handler calls if main() returns, and its own vector table, whose
 * entries common to every Cortex-M are CORTEXM_SYSTEM_VECTORS. */
#ifndef FRICTEX_CORTEXM_H
#define FRICTEX_CORTEXM_H

#include <stddef.h>
#include <stdint.h>

#include "../core/device.h"

extern uint32_t _estack;
void reset(void);
void fault(void);

/* The stack, reset, and fault() for NMI, HardFault, SVCall and PendSV. */
#define CORTEXM_SYSTEM_VECTORS                                                             \
    [0] = (uintptr_t)&_estack, [1] = (uintptr_t)reset, [2] = (uintptr_t)fault,             \
    [3] = (uintptr_t)fault, [11] = (uintptr_t)fault, [14] = (uintptr_t)fault

/* A port's fw_config from its board.h (BOARD_CHANNELS, BOARD_RATE_HZ, BOARD_BUFFER,
 * BOARD_WATCHDOG_MS, BOARD_RAMP_MS, BOARD_NAME), the per-channel limits as arguments. */
#define CORTEXM_BOARD_CONFIG(...)                                                          \
    {                                                                                      \
        .channels = BOARD_CHANNELS, .rate_mhz = BOARD_RATE_HZ * 1000u,                     \
        .buffer_samples = BOARD_BUFFER, .watchdog_ms = BOARD_WATCHDOG_MS,                  \
        .ramp_ms = BOARD_RAMP_MS, .limits = {__VA_ARGS__}, .name = BOARD_NAME,             \
        .protocol_version = FW_NEWEST_VERSION,                                             \
    }

/* One turn of a port's main loop for what the link brought: the bytes received so far
 * (``read``, the port's uart_read) handed to the core, after the watchdog trip the sample
 * interrupt may have noted. Returns how many bytes there were. Frames are timestamped
 * now, not when their bytes arrived: the watchdog trips up to one main-loop latency late
 * (at most what the receive ring covers, 2.6 ms for 256 bytes at 1 Mbaud), a margin
 * PROTOCOL.md 5.3 counts against its 50 ms. */
static inline size_t cortexm_take_bytes(fw_device *d, size_t (*read)(uint8_t *, size_t))
{
    uint8_t chunk[64];
    size_t n = read(chunk, sizeof chunk);
    fw_poll(d);
    if (n)
        fw_receive(d, chunk, n, d->tick);
    return n;
}

/* fw_hal.lock: mask interrupts (the sample interrupt shares the device core). */
static inline void cortexm_lock(void *ctx)
{
    (void)ctx;
    __asm volatile("cpsid i" ::: "memory");
}

/* fw_hal.unlock */
static inline void cortexm_unlock(void *ctx)
{
    (void)ctx;
    __asm volatile("cpsie i" ::: "memory");
}

#endif
