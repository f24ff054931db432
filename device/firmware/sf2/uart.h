/* The link on MMUART_0 (a 16550) with rings: received bytes are taken by its RX interrupt
 * from the 16-byte FIFO, so they never wait for the main loop; sending never waits for
 * the line: the main loop moves queued bytes out while the UART takes them (QEMU's 16550
 * passes each byte to its character device at once). */
#ifndef UART_H
#define UART_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

void uart_init(void);
/* Bytes received so far, at most cap; 0 if none. */
size_t uart_read(uint8_t *p, size_t cap);
/* Whether received bytes wait in the ring (call with interrupts off before sleeping). */
bool uart_rx_pending(void);
/* Queue link bytes to send; drops what does not fit (the host's CRC check counts it). */
void uart_write(void *ctx, const uint8_t *p, size_t n);
/* Move queued bytes to the UART while it takes them; true when nothing is left. */
bool uart_flush(void);

#endif
