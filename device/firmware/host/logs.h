/* The host port's CSV logs, in the reference device's formats (device/link/simdevice.py):
 * played samples (--log), one row per tick (--plate-log); and, for measuring the
 * watchdog from outside the core, the receive log (--rx-log): t_s,frames_ok,discarded,
 * core_t_s whenever a read from the port changed either count. t_s is when the core took
 * the read (its watchdog counts from there); core_t_s is how far its clock had played
 * then: a port descheduled for a while plays the ticks between the two after the read,
 * so the host's silence as the core saw it ends at core_t_s. */
#ifndef HOST_LOGS_H
#define HOST_LOGS_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "../core/device.h"

typedef struct {
    FILE *played, *plate, *rx;
    const char *played_path, *plate_path, *rx_path;
    unsigned channels;
    bool phases;
    bool lost; /* a log was lost: a write, flush or close the file system refused */
} host_logs;

/* Opens the logs whose path is not NULL; false (errno set) if one cannot be opened. */
bool host_logs_open(host_logs *l, unsigned channels, bool phases, const char *played,
                    const char *plate, const char *rx);
void host_logs_tick(host_logs *l, double t_s, const fw_output *o, const double *plate_um);
void host_logs_rx(host_logs *l, double t_s, uint32_t frames_ok, uint32_t discarded,
                  double core_t_s);
/* Flush and close: a log whose writes the file system refused (a full disk, /dev/full) is
 * said once on stderr, naming it, and closed (its rows from then on are dropped; the
 * device goes on); l->lost says one was. */
void host_logs_flush(host_logs *l);
void host_logs_close(host_logs *l);

#endif
