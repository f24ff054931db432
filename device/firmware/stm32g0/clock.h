#ifndef CLOCK_H
#define CLOCK_H

/* 64 MHz from HSI16 through the PLL (RM0444 5.2.4). */
void clock_init(void);

/* The independent watchdog: resets the chip unless kicked every BOARD_IWDG_MS. */
void iwdg_init(void);
void iwdg_kick(void);

#endif
