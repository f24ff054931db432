/* The Cortex-M0+ port: NUCLEO-G071RB, USART2 at 1 Mbaud, TIM6 sample clock, DAC1 outputs
 * (see README.md for the wiring and first power-up). */
#include "../core/device.h"
#include "../cortexm/cortexm.h"
#include "board.h"
#include "clock.h"
#include "sample_clock.h"
#include "uart.h"

static fw_device device;

static const fw_hal hal = {uart_write, NULL, NULL, cortexm_lock, cortexm_unlock, NULL}; /* no sensors wired */

static const fw_config config = CORTEXM_BOARD_CONFIG(BOARD_LIMIT, BOARD_LIMIT);

int main(void)
{
    clock_init();
    iwdg_init();
    uart_init();
    fw_init(&device, &config, &hal, NULL);
    sample_clock_start(&device);
    for (;;) {
        if (!cortexm_take_bytes(&device, uart_read))
            __asm volatile("wfi"); /* until the next byte or sample */
    }
}
