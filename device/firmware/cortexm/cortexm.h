/* What every Cortex-M port shares: the reset handler (reset.c) and the interrupt mask
 * that guards the device core (fw_hal's lock and unlock). Each port defines fault(),
 * which the reset handler calls if main() returns, and its own vector table, whose
 * entries common to every Cortex-M are CORTEXM_SYSTEM_VECTORS. */
#ifndef FRICTEX_CORTEXM_H
#define FRICTEX_CORTEXM_H

#include <stdint.h>

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
