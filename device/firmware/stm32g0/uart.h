/* USART2 with interrupt-driven rings: receive never waits for the main loop, transmit
 * never waits for the line (a full ring drops, as PROTOCOL.md lets a device do). */
#ifndef UART_H
#define UART_H

#include <stddef.h>
#include <stdint.h>

void uart_init(void);
/* Bytes received so far, at most cap; 0 if none. */
size_t uart_read(uint8_t *p, size_t cap);
/* Queue bytes to send; drops what does not fit. */
void uart_write(void *ctx, const uint8_t *p, size_t n);

#endif
