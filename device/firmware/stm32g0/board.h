/* NUCLEO-G071RB: STM32G071RB (Cortex-M0+, 64 MHz, 128 KiB flash, 36 KiB RAM; the build
 * is linked into a 32 KiB flash / 8 KiB RAM budget). What the board offers the host. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "frictex fw stm32g071"
#define BOARD_SYSCLK_HZ 64000000u
#define BOARD_BAUD 1000000u /* USART2, 8N1, on the ST-LINK's virtual COM port */
#define BOARD_RATE_HZ 10000u /* sample clock: TIM6 update, also the DAC trigger */
#define BOARD_CHANNELS 2     /* DAC1 OUT1 = PA4 (ch0), OUT2 = PA5 (ch1) */
#define BOARD_BUFFER 400     /* samples per channel: 40 ms at 10 kHz */
#define BOARD_LIMIT 16384u   /* 4 um per channel; the DAC's full scale is this limit */
#define BOARD_WATCHDOG_MS 25
#define BOARD_RAMP_MS 20
#define BOARD_IWDG_MS 20 /* the sample interrupt stopped this long: reset (outputs to 0 V) */

#if (BOARD_SYSCLK_HZ % BOARD_RATE_HZ) || (BOARD_SYSCLK_HZ % BOARD_BAUD)
#error "the sample rate and the baud rate must divide the system clock"
#endif

#endif
