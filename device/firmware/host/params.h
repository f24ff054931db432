/* The host port's configuration in the reference device's units and with its checks
 * (device/link/simdevice.py DeviceConfig), turned into the core's fw_config. */
#ifndef HOST_PARAMS_H
#define HOST_PARAMS_H

#include <stdbool.h>

#include "../core/device.h"

typedef struct {
    unsigned long channels;
    double rate_hz;
    double limits_um[FW_MAX_CHANNELS];
    unsigned n_limits; /* 1: the same limit for every channel */
    unsigned long buffer_samples;
    double bandwidth_hz;
    unsigned long watchdog_ms, ramp_ms;
    bool phases, sensor, has_force, has_lateral;
    double force_n;
    double lateral_n; /* constant lateral force in ForceReports, if has_lateral */
    const char *name; /* NULL: "frictex fw (host port)" */
    unsigned long protocol_version; /* newest spoken */
} host_params;

void host_params_default(host_params *p);

/* NULL and *cfg filled, or what is wrong (a static string, valid until the next call). */
const char *host_params_to_config(const host_params *p, fw_config *cfg);

#endif
