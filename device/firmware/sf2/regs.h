/* The few M2S010 registers this port touches (SmartFusion2 MSS user guide: MMUART, a
 * 16550; the MSS timer; the Cortex-M3 system control space). Kept here so the build
 * needs nothing but arm-none-eabi-gcc. */
#ifndef REGS_H
#define REGS_H

#include <stdint.h>

#define REG(addr) (*(volatile uint32_t *)(addr))

/* MMUART_0 at 0x40000000 (QEMU's first -serial) is the link: 16550 registers 4 bytes apart. */
#define UART0_RBR REG(0x40000000u) /* receive; THR on write, DLL with LCR.DLAB */
#define UART0_THR REG(0x40000000u)
#define UART0_DLL REG(0x40000000u)
#define UART0_IER REG(0x40000004u) /* DLM with LCR.DLAB */
#define UART0_DLM REG(0x40000004u)
#define UART0_FCR REG(0x40000008u)
#define UART0_LCR REG(0x4000000Cu)
#define UART0_LSR REG(0x40000014u)
#define UART_IER_RDA (1u << 0)        /* data available, or the FIFO's timeout */
#define UART_FCR_ENABLE_14 0xC7u     /* FIFOs on and cleared, interrupt at 14 bytes */
#define UART_LCR_DLAB 0x80u
#define UART_LCR_8N1 0x03u
#define UART_LSR_DR (1u << 0)
#define UART_LSR_THRE (1u << 5)
#define IRQ_UART0 10u

/* MSS timer 1: a 32-bit down-counter at the APB clock, periodic. */
#define TIM1_LOADVAL REG(0x40004004u)
#define TIM1_CTRL REG(0x4000400Cu)
#define TIM1_RIS REG(0x40004010u)
#define TIM_CTRL_ENABLE (1u << 0)
#define TIM_CTRL_INTEN (1u << 2)
#define IRQ_TIMER1 14u

#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_CLKSOURCE (1u << 2) /* the processor clock */
#define SYST_MAX 0xFFFFFFu

#define NVIC_ISER REG(0xE000E100u)
#define NVIC_IPR(n) (*(volatile uint8_t *)(0xE000E400u + (n))) /* byte access on M3 */

#endif
