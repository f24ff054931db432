#include "sample_clock.h"

#include "board.h"
#include "clock.h"
#include "regs.h"

static fw_device *device;
static uint32_t scale[BOARD_CHANNELS]; /* counts to DAC codes, Q16: the limit is full scale */

static uint32_t dac_code(unsigned ch, uint16_t amp)
{
    return (amp * scale[ch]) >> 16; /* amp <= limit, so the product fits 32 bits */
}

void sample_clock_start(fw_device *d)
{
    device = d;
    for (unsigned ch = 0; ch < BOARD_CHANNELS; ch++)
        scale[ch] = (4095u << 16) / d->cfg.limits[ch];
    RCC_APBENR1 |= RCC_APBENR1_DAC1EN | RCC_APBENR1_TIM6EN;
    DAC_DHR12RD = 0;
    uint32_t channel = DAC_CR_EN1 | DAC_CR_TEN1 | DAC_CR_TSEL1_TIM6;
    DAC_CR = channel | (channel << DAC_CR_CH2_SHIFT);
    TIM6_PSC = 0;
    TIM6_ARR = BOARD_SYSCLK_HZ / BOARD_RATE_HZ - 1u;
    TIM6_CR2 = TIM_CR2_MMS_UPDATE;
    TIM6_DIER = 1u; /* update interrupt */
    NVIC_ISER = 1u << IRQ_TIM6_DAC;
    TIM6_CR1 = 1u; /* count */
}

/* Per sample: the core's tick, two multiplies and one store to the DAC. */
void tim6_irq(void)
{
    TIM6_SR = 0;
    const fw_output *o = fw_tick(device);
    DAC_DHR12RD = dac_code(0, o->amp[0]) | (dac_code(1, o->amp[1]) << 16);
    iwdg_kick();
}
