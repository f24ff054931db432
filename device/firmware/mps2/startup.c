/* The vector table of the MPS2-AN385 (Cortex-M3: 16 system entries, 32 IRQs); reset is
 * ../cortexm/reset.c. */
#include "../cortexm/cortexm.h"

void systick_irq(void);
void uart0_rx_irq(void);

/* Any fault or stray interrupt: stop (QEMU keeps running; the host's link reports the
 * silent device). */
void fault(void)
{
    for (;;) {
        __asm volatile("wfi");
    }
}

__attribute__((section(".isr_vector"), used)) const uintptr_t vectors[16 + 32] = {
    CORTEXM_SYSTEM_VECTORS,
    [4] = (uintptr_t)fault, /* MemManage */
    [5] = (uintptr_t)fault, /* BusFault */
    [6] = (uintptr_t)fault, /* UsageFault */
    [15] = (uintptr_t)systick_irq,
    [16 + 0] = (uintptr_t)uart0_rx_irq, /* the other IRQs are never enabled */
};
