#include "params.h"

#include <math.h>
#include <stdio.h>

#define STEP_UM (1.0 / 4096.0)
#define AMPLITUDE_MAX_UM (65535 * STEP_UM)

static char message[200];

void host_params_default(host_params *p)
{
    *p = (host_params){
        .channels = 1, .rate_hz = 10000.0, .limits_um = {4.0}, .n_limits = 1,
        .buffer_samples = 4096, .bandwidth_hz = 400.0, .watchdog_ms = 25, .ramp_ms = 20,
        .protocol_version = FW_NEWEST_VERSION,
    };
}

static const char *fail(const char *name, const char *expected)
{
    snprintf(message, sizeof message, "%s: expected %s", name, expected);
    return message;
}

const char *host_params_to_config(const host_params *p, fw_config *cfg)
{
    char range[120];
    if (p->channels < 1 || p->channels > FW_MAX_CHANNELS) {
        snprintf(range, sizeof range, "1 to %d (this build)", FW_MAX_CHANNELS);
        return fail("channels", range);
    }
    if (!(p->rate_hz > 0 && p->rate_hz < 4e6))
        return fail("rate_hz", "in (0, 4e6) Hz");
    if (p->n_limits != 1 && p->n_limits != p->channels) {
        snprintf(range, sizeof range, "1 or %lu values", p->channels);
        return fail("limits_um", range);
    }
    for (unsigned i = 0; i < p->n_limits; i++)
        if (!(p->limits_um[i] >= STEP_UM && p->limits_um[i] <= AMPLITUDE_MAX_UM))
            return fail("limits_um", "in [1/4096, 15.9998] um (one count to the wire's top)");
    if (p->buffer_samples < 2 || p->buffer_samples > FW_STORE_WORDS / p->channels) {
        snprintf(range, sizeof range, "2 to %lu samples for %lu channel(s) (this build)",
                 (unsigned long)FW_STORE_WORDS / p->channels, p->channels);
        return fail("buffer_samples", range);
    }
    /* any rate: the board's pole exp(-2 pi f_c / f_s) is in [0, 1) (PROTOCOL.md 5.4) */
    if (!(p->bandwidth_hz > 0 && isfinite(p->bandwidth_hz)))
        return fail("bandwidth_hz", "positive and finite");
    if (p->watchdog_ms < 1 || p->watchdog_ms > 49)
        return fail("watchdog_ms", "in [1, 49] ms");
    if (p->ramp_ms > 50 - p->watchdog_ms) {
        snprintf(range, sizeof range, "in [0, %lu] ms: watchdog_ms + ramp_ms must not exceed "
                 "50 ms (PROTOCOL.md 5.3)", 50 - p->watchdog_ms);
        return fail("ramp_ms", range);
    }
    if (p->has_force && !(p->force_n >= 0 && p->force_n <= 65.0))
        return fail("force_n", "in [0, 65] N");
    if (p->protocol_version < 1 || p->protocol_version > FW_NEWEST_VERSION) {
        snprintf(range, sizeof range, "in [1, %u]", FW_NEWEST_VERSION);
        return fail("protocol_version", range);
    }
    if (p->has_lateral && !(p->lateral_n >= -8.0 && p->lateral_n <= 8.0))
        return fail("lateral_n", "in [-8, 8] N");
    if (p->has_lateral && p->protocol_version < 3)
        return fail("protocol_version", "3 for force reports (lateral_n)");

    *cfg = (fw_config){
        .channels = (uint8_t)p->channels,
        .phases = p->phases,
        .rate_mhz = (uint32_t)llround(p->rate_hz * 1000.0),
        .buffer_samples = (uint32_t)p->buffer_samples,
        .watchdog_ms = (uint16_t)p->watchdog_ms,
        .ramp_ms = (uint16_t)p->ramp_ms,
        .name = p->name ? p->name : "frictex fw (host port)",
        .protocol_version = (uint8_t)p->protocol_version,
        .force_decimation = 4,
    };
    for (unsigned ch = 0; ch < p->channels; ch++) {
        double um = p->limits_um[p->n_limits == 1 ? 0 : ch];
        /* floor to a whole count, so a clamped value is never above the limit */
        cfg->limits[ch] = (uint16_t)floor(um / STEP_UM + 1e-9);
    }
    return fw_config_check(cfg);
}
