/* The few LM3S6965 registers this port touches (Stellaris LM3S6965 data sheet: the PL011
 * UART; the Cortex-M3 system control space). Kept here so the build needs nothing but
 * arm-none-eabi-gcc. */
#ifndef REGS_H
#define REGS_H

#include <stdint.h>

#define REG(addr) (*(volatile uint32_t *)(addr))

/* PL011 UART0 at 0x4000C000 (QEMU's first -serial) is the link. */
#define UART0_DR REG(0x4000C000u)
#define UART0_FR REG(0x4000C018u)
#define UART0_LCRH REG(0x4000C02Cu)
#define UART0_CR REG(0x4000C030u)
#define UART0_IMSC REG(0x4000C038u)
#define UART0_ICR REG(0x4000C044u)
#define UART_FR_RXFE (1u << 4)
#define UART_FR_TXFF (1u << 5)
#define UART_LCRH_FEN (1u << 4)     /* the 16-byte FIFOs */
#define UART_LCRH_WLEN8 (3u << 5)
#define UART_CR_UARTEN (1u << 0)
#define UART_CR_TXE (1u << 8)
#define UART_CR_RXE (1u << 9)
#define UART_INT_RX (1u << 4)
#define IRQ_UART0 5u

/* General-purpose timer 0 (timer A, 32-bit periodic) and its clock gate. */
#define RCGC1 REG(0x400FE104u)
#define RCGC1_TIMER0 (1u << 16)
#define GPTM0_CFG REG(0x40030000u)
#define GPTM0_TAMR REG(0x40030004u)
#define GPTM0_CTL REG(0x4003000Cu)
#define GPTM0_IMR REG(0x40030018u)
#define GPTM0_ICR REG(0x40030024u)
#define GPTM0_TAILR REG(0x40030028u)
#define GPTM_TAMR_PERIODIC 2u
#define GPTM_CTL_TAEN (1u << 0)
#define GPTM_INT_TATO (1u << 0)
#define IRQ_TIMER0A 19u

#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CLKSOURCE (1u << 2) /* the processor clock */
#define SYST_MAX 0xFFFFFFu

#define NVIC_ISER REG(0xE000E100u)
#define NVIC_IPR(n) (*(volatile uint8_t *)(0xE000E400u + (n))) /* byte access on M3 */
#define SCB_SHPR3 REG(0xE000ED20u) /* SysTick priority: bits 31:24 */

#endif
