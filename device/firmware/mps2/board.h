/* MPS2-AN385 as QEMU emulates it (qemu-system-arm -M mps2-an385): a Cortex-M3 at 25 MHz
 * with CMSDK APB UARTs. What the board offers the host; override with -D. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "frictex fw mps2-an385"
#define BOARD_SYSCLK_HZ 25000000u /* QEMU's mps2 SYSCLK, SysTick's processor clock */
#ifndef BOARD_RATE_HZ
#define BOARD_RATE_HZ 10000u /* sample clock: SysTick */
#endif
#ifndef BOARD_CHANNELS
#define BOARD_CHANNELS 1
#endif
#define BOARD_BUFFER 4096  /* samples per channel, as the host port's default */
#define BOARD_LIMIT 16384u /* 4 um per channel */
#define BOARD_WATCHDOG_MS 25
#define BOARD_RAMP_MS 20
#define BOARD_PLAYED_LOG "played.bin" /* opened through semihosting in QEMU's folder */
#define BOARD_CATCH_UP 1000u /* most ticks one sample interrupt plays (100 ms) */
#define BOARD_BAUDDIV 16u /* QEMU does not pace the UART; 16 is its smallest legal divider */

#define BOARD_TICK_CYCLES (BOARD_SYSCLK_HZ / BOARD_RATE_HZ)

#if BOARD_SYSCLK_HZ % BOARD_RATE_HZ
#error "the sample rate must divide the system clock"
#endif

#endif
