/* Reset and the vector table of the MPS2-AN385 (Cortex-M3: 16 system entries, 32 IRQs). */
#include <stdint.h>
#include <string.h>

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);
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
    [4] = (uintptr_t)fault,  /* MemManage */
    [5] = (uintptr_t)fault,  /* BusFault */
    [6] = (uintptr_t)fault,  /* UsageFault */
    [11] = (uintptr_t)fault, /* SVCall */
    [14] = (uintptr_t)fault, /* PendSV */
    [15] = (uintptr_t)systick_irq,
    [16 + 0] = (uintptr_t)uart0_rx_irq, /* the other IRQs are never enabled */
};
