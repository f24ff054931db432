/* The few MPS2-AN385 registers this port touches (ARM AN385, CMSDK APB UART; the
 * Cortex-M3 system control space). Kept here so the build needs nothing but
 * arm-none-eabi-gcc. */
#ifndef REGS_H
#define REGS_H

#include <stdint.h>

#define REG(addr) (*(volatile uint32_t *)(addr))

/* CMSDK APB UART n at 0x40004000 + 0x1000 n: UART0 (QEMU's first -serial) is the link. */
#define UART_DATA(n) REG(0x40004000u + 0x1000u * (n))
#define UART_STATE(n) REG(0x40004004u + 0x1000u * (n))
#define UART_CTRL(n) REG(0x40004008u + 0x1000u * (n))
#define UART_INTCLEAR(n) REG(0x4000400Cu + 0x1000u * (n))
#define UART_BAUDDIV(n) REG(0x40004010u + 0x1000u * (n))
#define UART_STATE_TXFULL (1u << 0)
#define UART_STATE_RXFULL (1u << 1)
#define UART_CTRL_TX_EN (1u << 0)
#define UART_CTRL_RX_EN (1u << 1)
#define UART_CTRL_RX_INTEN (1u << 3)
#define UART_INT_RX (1u << 1)
#define IRQ_UART0_RX 0u

/* CMSDK APB timer 0: a 32-bit down-counter at the system clock. */
#define TIMER0_CTRL REG(0x40000000u)
#define TIMER0_VALUE REG(0x40000004u)
#define TIMER0_RELOAD REG(0x40000008u)
#define TIMER_CTRL_EN (1u << 0)

#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CLKSOURCE (1u << 2) /* the processor clock */

#define NVIC_ISER REG(0xE000E100u)
#define NVIC_IPR(n) (*(volatile uint8_t *)(0xE000E400u + (n))) /* byte access on M3 */
#define SCB_SHPR3 REG(0xE000ED20u) /* SysTick priority: bits 31:24 */

#endif
