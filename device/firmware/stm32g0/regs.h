/* The few STM32G0 registers this port touches (RM0444; addresses and bits as in ST's
 * stm32g071xx.h). Kept here so the build needs nothing but arm-none-eabi-gcc. */
#ifndef REGS_H
#define REGS_H

#include <stdint.h>

#define REG(addr) (*(volatile uint32_t *)(addr))

#define FLASH_ACR REG(0x40022000u)
#define RCC_CR REG(0x40021000u)
#define RCC_CFGR REG(0x40021008u)
#define RCC_PLLCFGR REG(0x4002100Cu)
#define RCC_IOPENR REG(0x40021034u)
#define RCC_APBENR1 REG(0x4002103Cu)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_APBENR1_TIM6EN (1u << 4)
#define RCC_APBENR1_USART2EN (1u << 17)
#define RCC_APBENR1_DAC1EN (1u << 29)

#define GPIOA_MODER REG(0x50000000u)
#define GPIOA_PUPDR REG(0x5000000Cu)
#define GPIOA_AFRL REG(0x50000020u)

#define USART2_CR1 REG(0x40004400u)
#define USART2_BRR REG(0x4000440Cu)
#define USART2_ISR REG(0x4000441Cu)
#define USART2_ICR REG(0x40004420u)
#define USART2_RDR REG(0x40004424u)
#define USART2_TDR REG(0x40004428u)
#define USART_CR1_UE (1u << 0)
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR1_FIFOEN (1u << 29)
#define USART_ISR_ERRORS (0xFu) /* PE FE NE ORE; ICR clears them at the same bits */
#define USART_ISR_RXNE (1u << 5)
#define USART_ISR_TXE (1u << 7)

#define TIM6_CR1 REG(0x40001000u)
#define TIM6_CR2 REG(0x40001004u)
#define TIM6_DIER REG(0x4000100Cu)
#define TIM6_SR REG(0x40001010u)
#define TIM6_PSC REG(0x40001028u)
#define TIM6_ARR REG(0x4000102Cu)
#define TIM_CR2_MMS_UPDATE (2u << 4) /* TRGO on update: triggers the DAC */

#define DAC_CR REG(0x40007400u)
#define DAC_DHR12RD REG(0x40007420u) /* both channels in one store: ch1 11:0, ch2 27:16 */
#define DAC_CR_EN1 (1u << 0)
#define DAC_CR_TEN1 (1u << 1)
#define DAC_CR_TSEL1_TIM6 (5u << 2)
#define DAC_CR_CH2_SHIFT 16u

#define IWDG_KR REG(0x40003000u)
#define IWDG_PR REG(0x40003004u)
#define IWDG_RLR REG(0x40003008u)
#define IWDG_SR REG(0x4000300Cu)

#define NVIC_ISER REG(0xE000E100u)
#define NVIC_IPR(n) REG(0xE000E400u + 4u * ((n) / 4u)) /* word access only on M0+ */

#define IRQ_TIM6_DAC 17u
#define IRQ_USART2 28u

#endif
