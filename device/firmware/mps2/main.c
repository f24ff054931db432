/* The QEMU port: MPS2-AN385 (Cortex-M3), the link on UART0, SysTick as the sample clock,
 * each played sample logged on UART1 (see README.md, "The QEMU board"). When a host's
 * Stop has played out it leaves QEMU through semihosting, as the host port's --once. */
#include <string.h>

#include "../core/device.h"
#include "board.h"
#include "regs.h"
#include "uart.h"

static fw_device device;
static volatile uint32_t log_dropped;

static void lock(void *ctx)
{
    (void)ctx;
    __asm volatile("cpsid i" ::: "memory");
}

static void unlock(void *ctx)
{
    (void)ctx;
    __asm volatile("cpsie i" ::: "memory");
}

static const fw_hal hal = {uart_write, NULL, NULL, lock, unlock, NULL}; /* no sensors */

static const fw_config config = {
    .channels = BOARD_CHANNELS,
    .rate_mhz = BOARD_RATE_HZ * 1000u,
    .buffer_samples = BOARD_BUFFER,
    .watchdog_ms = BOARD_WATCHDOG_MS,
    .ramp_ms = BOARD_RAMP_MS,
    .limits = {BOARD_LIMIT},
    .name = BOARD_NAME,
    .protocol_version = FW_NEWEST_VERSION,
};

/* Per sample: the core's tick; a played sample is logged as its number (u32) and its
 * setpoint per channel (u16 counts), little-endian. */
void systick_irq(void)
{
    const fw_output *o = fw_tick(&device);
    if (!o->played)
        return;
    uint8_t rec[4 + 2 * BOARD_CHANNELS];
    uint32_t index = (uint32_t)o->index;
    memcpy(rec, &index, 4);
    memcpy(rec + 4, o->amp, 2 * BOARD_CHANNELS);
    if (!log_write(rec, sizeof rec))
        log_dropped++;
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
    fw_init(&device, &config, &hal, NULL);
    SCB_SHPR3 &= 0x00FFFFFFu; /* SysTick at the highest priority */
    SYST_RVR = BOARD_SYSCLK_HZ / BOARD_RATE_HZ - 1u;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_TICKINT | SYST_CSR_CLKSOURCE;
    for (;;) {
        uint8_t chunk[64];
        size_t n = uart_read(chunk, sizeof chunk);
        fw_poll(&device); /* a watchdog trip the sample interrupt noted */
        if (n)
            fw_receive(&device, chunk, n, device.tick);
        bool sent = uart_flush();
        if (fw_finished(&device) && sent && log_dropped == 0)
            semihosting_exit(); /* a dropped log record: stay, the test times out on it */
        __asm volatile("cpsid i" ::: "memory");
        if (!uart_rx_pending())
            __asm volatile("wfi"); /* until the next byte or sample */
        __asm volatile("cpsie i" ::: "memory");
    }
}
