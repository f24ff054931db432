/* What a port gives the core. The sample clock and the outputs stay with the port: its
 * timer calls fw_tick() once per sample and writes the returned setpoints (amplitude,
 * and phase if it drives phases) to its DAC or PWM; its main loop hands received bytes
 * to fw_receive(). */
#ifndef FW_HAL_H
#define FW_HAL_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
    /* Reply bytes. Never blocks: what does not fit the port's queue is dropped (a UART
     * does not wait either; the host counts the damage). */
    void (*serial_write)(void *ctx, const uint8_t *p, size_t n);
    /* Measured plate amplitude of channel ch (counts of 1/4096 um); NULL: no sensor. */
    uint16_t (*amplitude_sensor)(void *ctx, unsigned ch);
    /* Normal force (mN); NULL: no sensor. */
    uint16_t (*force_sensor)(void *ctx);
    /* Keep fw_tick() out while fw_receive() changes shared state; NULL when both run
     * in one thread. Held for a few dozen instructions at a time. */
    void (*lock)(void *ctx);
    void (*unlock)(void *ctx);
    /* Lateral and normal force now, counts of 1/4096 N (PROTOCOL.md 4.9): out[0] lateral,
     * out[1] normal. Called by fw_tick() (in the sample interrupt) on every tick that
     * advances the play position: a conversion result read, nothing slower. NULL: no
     * lateral force sensor (Info flags bit 3 off, no ForceReports). */
    void (*force_pair)(void *ctx, int16_t out[2]);
} fw_hal;

#endif
