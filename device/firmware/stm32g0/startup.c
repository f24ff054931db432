/* The vector table of the STM32G0 (Cortex-M0+: 16 system entries, 32 IRQs); reset is
 * ../cortexm/reset.c. */
#include "../cortexm/cortexm.h"
#include "regs.h"

void tim6_irq(void);
void usart2_irq(void);

/* Any fault or stray interrupt: zero both DAC channels (the running TIM6 latches the
 * zero at its next update) and stop; the independent watchdog then resets the chip. */
void fault(void)
{
    DAC_DHR12RD = 0;
    for (;;) {
    }
}

__attribute__((section(".isr_vector"), used)) const uintptr_t vectors[16 + 32] = {
    CORTEXM_SYSTEM_VECTORS,
    [15] = (uintptr_t)fault, /* SysTick */
    [16 + IRQ_TIM6_DAC] = (uintptr_t)tim6_irq,
    [16 + IRQ_USART2] = (uintptr_t)usart2_irq, /* the other IRQs are never enabled */
};
