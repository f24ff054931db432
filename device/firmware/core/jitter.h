/* The jitter buffer (PROTOCOL.md 4.3, 5.1): received samples by slot, a bit per slot
 * saying whether it holds one, and the count of held samples. Which sample number a
 * slot holds is the device's business (device.c keeps the slot of the play position). */
#ifndef FW_JITTER_H
#define FW_JITTER_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "fw_limits.h"

typedef struct {
    uint16_t amp[FW_STORE_WORDS]; /* slot-major: slot * channels + ch */
#if FW_PHASES
    uint16_t phase[FW_STORE_WORDS];
#endif
    uint32_t filled[(FW_STORE_WORDS + 31u) / 32u];
    uint32_t cap; /* slots (buffer_samples) */
    uint32_t level;
    uint8_t channels;
} fw_jitter;

static inline void fw_jitter_flush(fw_jitter *j)
{
    memset(j->filled, 0, 4u * ((j->cap + 31u) / 32u));
    j->level = 0;
}

static inline bool fw_jitter_has(const fw_jitter *j, uint32_t slot)
{
    return (j->filled[slot >> 5] >> (slot & 31u)) & 1u;
}

/* Store one sample (channels values each); a repeated slot is overwritten. */
static inline void fw_jitter_put(fw_jitter *j, uint32_t slot, const uint16_t *amp,
                                 const uint16_t *phase)
{
    uint32_t bit = 1u << (slot & 31u);
    if (!(j->filled[slot >> 5] & bit)) {
        j->filled[slot >> 5] |= bit;
        j->level++;
    }
    memcpy(&j->amp[slot * j->channels], amp, 2u * j->channels);
#if FW_PHASES
    if (phase)
        memcpy(&j->phase[slot * j->channels], phase, 2u * j->channels);
#else
    (void)phase;
#endif
}

/* Move the sample out of a slot that holds one. */
static inline void fw_jitter_take(fw_jitter *j, uint32_t slot, uint16_t *amp, uint16_t *phase)
{
    j->filled[slot >> 5] &= ~(1u << (slot & 31u));
    j->level--;
    const uint16_t *a = &j->amp[slot * j->channels];
    for (unsigned c = 0; c < j->channels; c++)
        amp[c] = a[c];
#if FW_PHASES
    const uint16_t *p = &j->phase[slot * j->channels];
    for (unsigned c = 0; c < j->channels; c++)
        phase[c] = p[c];
#else
    (void)phase;
#endif
}

#endif
