/* Reset and the vector table of the STM32G0 (Cortex-M0+: 16 system entries, 32 IRQs). */
#include <stdint.h>
#include <string.h>

#include "regs.h"

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);
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

void reset(void)
{
    memcpy(&_sdata, &_sidata, (size_t)((char *)&_edata - (char *)&_sdata));
    memset(&_sbss, 0, (size_t)((char *)&_ebss - (char *)&_sbss));
    main();
    fault();
}

__attribute__((section(".isr_vector"), used)) const uintptr_t vectors[16 + 32] = {
    [0] = (uintptr_t)&_estack,
    [1] = (uintptr_t)reset,
    [2] = (uintptr_t)fault,  /* NMI */
    [3] = (uintptr_t)fault,  /* HardFault */
    [11] = (uintptr_t)fault, /* SVCall */
    [14] = (uintptr_t)fault, /* PendSV */
    [15] = (uintptr_t)fault, /* SysTick */
    [16 + IRQ_TIM6_DAC] = (uintptr_t)tim6_irq,
    [16 + IRQ_USART2] = (uintptr_t)usart2_irq, /* the other IRQs are never enabled */
};
