/* The sample clock and the outputs: TIM6 updates at BOARD_RATE_HZ and triggers both DAC
 * channels, so each new setpoint appears exactly on a clock edge whatever the interrupt
 * latency; its interrupt runs fw_tick() and loads the next setpoints. */
#ifndef SAMPLE_CLOCK_H
#define SAMPLE_CLOCK_H

#include "../core/device.h"

void sample_clock_start(fw_device *d);

#endif
