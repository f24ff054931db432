/* Emcraft's SmartFusion2 SOM as QEMU emulates it (qemu-system-arm -M emcraft-sf2): a
 * Microsemi M2S010, Cortex-M3 at 142 MHz, with 16550 UARTs. What the board offers the
 * host; override with -D. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "frictex fw emcraft-sf2"
#define BOARD_SYSCLK_HZ 142000000u /* QEMU's M3 clock, SysTick's processor clock */
#define BOARD_TIMER_HZ 71000000u   /* the MSS timer's: the M3 clock / APB0's divider (2) */
#ifndef BOARD_RATE_HZ
#define BOARD_RATE_HZ 10000u /* sample clock: SysTick's count */
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
#ifndef BOARD_IRQ_TICKS
#define BOARD_IRQ_TICKS 5u /* sample periods per timer interrupt (2 kHz) */
#endif

#define BOARD_TICK_CYCLES (BOARD_SYSCLK_HZ / BOARD_RATE_HZ)

#if BOARD_SYSCLK_HZ % BOARD_RATE_HZ || BOARD_TIMER_HZ % BOARD_RATE_HZ
#error "the sample rate must divide the clocks"
#endif

#endif
