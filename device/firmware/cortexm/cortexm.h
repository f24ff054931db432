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
