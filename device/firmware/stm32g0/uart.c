#include "uart.h"

#include "board.h"
#include "regs.h"

/* Sizes are powers of two; at 1 Mbaud the receive ring covers 2.5 ms of main-loop
 * latency (the longest job, storing a 2038-sample block, takes about 1 ms). */
#define RX_SIZE 256u
#define TX_SIZE 256u

static volatile uint8_t rx[RX_SIZE], tx[TX_SIZE];
static volatile uint16_t rx_head, rx_tail, tx_head, tx_tail;

void uart_init(void)
{
    RCC_IOPENR |= 1u; /* GPIOA */
    RCC_APBENR1 |= RCC_APBENR1_USART2EN;
    /* PA2 = TX, PA3 = RX: alternate function 1; pull-up on RX so an open line idles */
    GPIOA_MODER = (GPIOA_MODER & ~(0xFu << 4)) | (0xAu << 4);
    GPIOA_AFRL = (GPIOA_AFRL & ~(0xFFu << 8)) | (0x11u << 8);
    GPIOA_PUPDR = (GPIOA_PUPDR & ~(3u << 6)) | (1u << 6);
    USART2_BRR = BOARD_SYSCLK_HZ / BOARD_BAUD;
    USART2_CR1 = USART_CR1_FIFOEN | USART_CR1_RXNEIE | USART_CR1_TE | USART_CR1_RE | USART_CR1_UE;
    NVIC_IPR(IRQ_USART2) |= 0x40u << (8u * (IRQ_USART2 % 4u)); /* below the sample clock */
    NVIC_ISER = 1u << IRQ_USART2;
}

size_t uart_read(uint8_t *p, size_t cap)
{
    size_t n = 0;
    uint16_t tail = rx_tail;
    while (n < cap && tail != rx_head) {
        p[n++] = rx[tail];
        tail = (uint16_t)((tail + 1u) & (RX_SIZE - 1u));
    }
    rx_tail = tail;
    return n;
}

void uart_write(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    for (size_t i = 0; i < n; i++) {
        uint16_t next = (uint16_t)((tx_head + 1u) & (TX_SIZE - 1u));
        if (next == tx_tail)
            break; /* full: the host's CRC check and counters see the loss */
        tx[tx_head] = p[i];
        tx_head = next;
    }
    __asm volatile("cpsid i" ::: "memory");
    USART2_CR1 |= USART_CR1_TXEIE;
    __asm volatile("cpsie i" ::: "memory");
}

void usart2_irq(void)
{
    uint32_t isr = USART2_ISR;
    if (isr & USART_ISR_ERRORS)
        USART2_ICR = isr & USART_ISR_ERRORS; /* a lost or damaged byte: the CRC catches it */
    while (USART2_ISR & USART_ISR_RXNE) {
        uint8_t b = (uint8_t)USART2_RDR;
        uint16_t next = (uint16_t)((rx_head + 1u) & (RX_SIZE - 1u));
        if (next != rx_tail) {
            rx[rx_head] = b;
            rx_head = next;
        }
    }
    while ((USART2_CR1 & USART_CR1_TXEIE) && (USART2_ISR & USART_ISR_TXE)) {
        if (tx_tail == tx_head) {
            USART2_CR1 &= ~USART_CR1_TXEIE;
            break;
        }
        USART2_TDR = tx[tx_tail];
        tx_tail = (uint16_t)((tx_tail + 1u) & (TX_SIZE - 1u));
    }
}
