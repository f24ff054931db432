#include "uart.h"

#include "board.h"
#include "regs.h"

/* Sizes are powers of two. Each ring has one writer and one reader, so the indices need
 * no lock: the writer owns the head, the reader the tail. */
#define RX_SIZE 1024u
#define TX_SIZE 1024u

typedef struct {
    volatile uint8_t *buf;
    uint32_t mask;
    volatile uint32_t head, tail;
} ring;

static volatile uint8_t rx_buf[RX_SIZE], tx_buf[TX_SIZE];
static ring rx = {rx_buf, RX_SIZE - 1u, 0, 0};
static ring tx = {tx_buf, TX_SIZE - 1u, 0, 0};
static volatile bool rx_masked; /* the receive interrupt is off: the ring was full */

static uint32_t ring_free(const ring *r) { return r->mask - ((r->head - r->tail) & r->mask); }

static void ring_put(ring *r, const uint8_t *p, size_t n)
{
    uint32_t head = r->head;
    for (size_t i = 0; i < n; i++) {
        r->buf[head] = p[i];
        head = (head + 1u) & r->mask;
    }
    r->head = head;
}

/* The received bytes the UART's FIFO holds, into the ring while it has room (else they
 * wait in the FIFO, and QEMU holds back what does not fit in it: nothing is lost). A full
 * ring masks the receive interrupt until uart_read has made room: the FIFO stays above
 * its level, so the interrupt would stay asserted, and a handler entered again and again
 * taking nothing left the main loop, which empties the ring, no time at all (QEMU: of a
 * 64 KiB burst of Heartbeats the device took 17 KiB, then answered nothing more). */
static void rx_drain(void)
{
    while (UART0_LSR & UART_LSR_DR) {
        if (!ring_free(&rx)) {
            UART0_IER &= ~UART_IER_RDA;
            rx_masked = true;
            return;
        }
        uint8_t b = (uint8_t)UART0_RBR;
        ring_put(&rx, &b, 1);
    }
}

void uart_init(void)
{
    UART0_LCR = UART_LCR_DLAB;
    UART0_DLL = 1u; /* QEMU does not pace the line; the divisor sets its FIFO timeout */
    UART0_DLM = 0u;
    UART0_LCR = UART_LCR_8N1;
    UART0_FCR = UART_FCR_ENABLE_14;
    UART0_IER = UART_IER_RDA;
    NVIC_IPR(IRQ_UART0) = 0x40u; /* below the sample clock (0) */
    NVIC_ISER = 1u << IRQ_UART0;
}

size_t uart_read(uint8_t *p, size_t cap)
{
    size_t n = 0;
    uint32_t tail = rx.tail;
    while (n < cap && tail != rx.head) {
        p[n++] = rx.buf[tail];
        tail = (tail + 1u) & rx.mask;
    }
    rx.tail = tail;
    __asm volatile("cpsid i" ::: "memory");
    if (rx_masked) {
        rx_masked = false;
        UART0_IER |= UART_IER_RDA;
    }
    rx_drain(); /* bytes held in the UART while the ring was full */
    __asm volatile("cpsie i" ::: "memory");
    return n;
}

bool uart_rx_pending(void) { return rx.head != rx.tail || (UART0_LSR & UART_LSR_DR); }

void uart_write(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    uint32_t room = ring_free(&tx);
    ring_put(&tx, p, n < room ? n : room);
}

bool uart_flush(void)
{
    uint32_t tail = tx.tail;
    while (tail != tx.head && (UART0_LSR & UART_LSR_THRE)) {
        UART0_THR = tx.buf[tail];
        tail = (tail + 1u) & tx.mask;
    }
    tx.tail = tail;
    return tail == tx.head;
}

void uart0_irq(void)
{
    rx_drain(); /* the interrupt clears once the FIFO is below its level, or empty */
}
