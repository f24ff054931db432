#include "clock.h"

#include "board.h"
#include "regs.h"

void clock_init(void)
{
    FLASH_ACR = (FLASH_ACR & ~7u) | 2u | (1u << 8) | (1u << 9); /* 2 wait states, prefetch, I-cache */
    while ((FLASH_ACR & 7u) != 2u) {
    }
    /* HSI16 / M 1 * N 8 = 128 MHz VCO, / R 2 = 64 MHz */
    RCC_PLLCFGR = 2u | (0u << 4) | (8u << 8) | (1u << 28) | (1u << 29);
    RCC_CR |= RCC_CR_PLLON;
    while (!(RCC_CR & RCC_CR_PLLRDY)) {
    }
    RCC_CFGR = (RCC_CFGR & ~7u) | 2u;
    while (((RCC_CFGR >> 3) & 7u) != 2u) {
    }
}

void iwdg_init(void)
{
    IWDG_KR = 0xCCCCu; /* start (and the 32 kHz LSI with it) */
    IWDG_KR = 0x5555u; /* unlock PR and RLR */
    IWDG_PR = 0;       /* LSI / 4: 8 counts per ms */
    IWDG_RLR = 8u * BOARD_IWDG_MS;
    while (IWDG_SR) {
    }
    IWDG_KR = 0xAAAAu;
}

void iwdg_kick(void) { IWDG_KR = 0xAAAAu; }
