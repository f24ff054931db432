/* The QEMU port: Emcraft's SmartFusion2 SOM (M2S010, Cortex-M3), the link on MMUART_0,
 * SysTick's count as the sample clock, each played sample logged through semihosting (see
 * README.md, "The QEMU board"). When a host's Stop has played out it leaves QEMU through
 * semihosting, as the host port's --once. */
#include "../core/device.h"
#include "../cortexm/cortexm.h"
#include "board.h"
#include "played_log.h"
#include "regs.h"
#include "uart.h"

static fw_device device;
static volatile uint32_t log_dropped;

static const fw_hal hal = {uart_write, NULL, NULL, cortexm_lock, cortexm_unlock, NULL}; /* no sensors */

static const fw_config config = CORTEXM_BOARD_CONFIG(BOARD_LIMIT);

/* The sample clock is SysTick's count, running free at the M3 clock (24 bits: it
 * wraps every 118 ms): MSS timer 1 interrupts every BOARD_IRQ_TICKS sample periods, and each
 * interrupt plays the ticks the count says are due. QEMU delivers a timer interrupt late
 * or not at all while the host runs something else (and each one costs its main loop a
 * wake-up: at 10 kHz they took a fifth of a host core), but the count follows the host's
 * clock; so an interrupt plays the ticks due since the last, as the host port does after
 * it was descheduled, and the output keeps the wall clock's pace (at most BOARD_CATCH_UP
 * ticks per interrupt; the rest at the next). A board plays one tick per interrupt. */
static uint32_t last_count, cycles_due;

void timer1_irq(void)
{
    TIM1_RIS = 1u;
    uint32_t now = SYST_CVR;
    cycles_due += (last_count - now) & SYST_MAX; /* a 24-bit down-counter */
    last_count = now;
    for (unsigned n = 0; cycles_due >= BOARD_TICK_CYCLES && n < BOARD_CATCH_UP; n++) {
        cycles_due -= BOARD_TICK_CYCLES;
        if (!played_log_note(fw_tick(&device)))
            log_dropped++;
    }
}

/* Semihosting SYS_EXIT with ADP_Stopped_ApplicationExit: QEMU exits with status 0. */
static void semihosting_exit(void)
{
    register uint32_t r0 __asm("r0") = 0x18u;
    register uint32_t r1 __asm("r1") = 0x20026u;
    __asm volatile("bkpt 0xab" : : "r"(r0), "r"(r1) : "memory");
}

int main(void)
{
    uart_init();
    played_log_open();
    fw_init(&device, &config, &hal, NULL);
    SYST_RVR = SYST_MAX;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_CLKSOURCE; /* counts, never interrupts */
    last_count = SYST_CVR;
    TIM1_LOADVAL = BOARD_IRQ_TICKS * (BOARD_TIMER_HZ / BOARD_RATE_HZ) - 1u;
    NVIC_IPR(IRQ_TIMER1) = 0x00u; /* the highest priority: above the UART */
    NVIC_ISER = 1u << IRQ_TIMER1;
    TIM1_CTRL = TIM_CTRL_ENABLE | TIM_CTRL_INTEN;
    for (;;) {
        cortexm_take_bytes(&device, uart_read);
        bool finished = fw_finished(&device);
        bool sent = uart_flush() & played_log_flush(device.tick, finished);
        if (finished && sent && log_dropped == 0)
            semihosting_exit(); /* a dropped log record: stay, the test times out on it */
        __asm volatile("cpsid i" ::: "memory");
        if (!uart_rx_pending())
            __asm volatile("wfi"); /* until the next byte or sample */
        __asm volatile("cpsie i" ::: "memory");
    }
}
