/* The vector table of the M2S010 (Cortex-M3: 16 system entries, 81 IRQs); reset is
 * ../cortexm/reset.c. */
#include "../cortexm/cortexm.h"

void timer1_irq(void);
void uart0_irq(void);

/* Any fault or stray interrupt: stop (QEMU keeps running; the host's link reports the
 * silent device). */
void fault(void)
{
    for (;;) {
        __asm volatile("wfi");
    }
}

__attribute__((section(".isr_vector"), used)) const uintptr_t vectors[16 + 81] = {
    CORTEXM_SYSTEM_VECTORS,
    [4] = (uintptr_t)fault, /* MemManage */
    [5] = (uintptr_t)fault, /* BusFault */
    [6] = (uintptr_t)fault, /* UsageFault */
    [16 + 10] = (uintptr_t)uart0_irq,
    [16 + 14] = (uintptr_t)timer1_irq, /* the other IRQs are never enabled */
};
