#include "logs.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <string.h>

#define STEP_UM (1.0 / 4096.0)
#define PHASE_STEP_RAD (2.0 * M_PI / 65536.0)

static FILE *open_csv(const char *path, bool *ok)
{
    if (!path)
        return NULL;
    FILE *f = fopen(path, "w");
    if (!f)
        *ok = false;
    return f;
}

bool host_logs_open(host_logs *l, unsigned channels, bool phases, const char *played,
                    const char *plate, const char *rx)
{
    bool ok = true;
    *l = (host_logs){open_csv(played, &ok), open_csv(plate, &ok), open_csv(rx, &ok),
                     played, plate, rx, channels, phases, false};
    if (l->played) {
        fputs("index", l->played);
        for (unsigned c = 0; c < channels; c++)
            fprintf(l->played, ",ch%u_um", c);
        for (unsigned c = 0; phases && c < channels; c++)
            fprintf(l->played, ",ch%u_phase_rad", c);
        fputc('\n', l->played);
    }
    if (l->plate) {
        fputs("t_s,state", l->plate);
        for (unsigned c = 0; c < channels; c++)
            fprintf(l->plate, ",ch%u_setpoint_um", c);
        for (unsigned c = 0; c < channels; c++)
            fprintf(l->plate, ",ch%u_plate_um", c);
        fputc('\n', l->plate);
    }
    if (l->rx)
        fputs("t_s,frames_ok,discarded,core_t_s\n", l->rx);
    return ok;
}

void host_logs_tick(host_logs *l, double t_s, const fw_output *o, const double *plate_um)
{
    if (l->played && o->played) {
        fprintf(l->played, "%" PRIu64, o->index);
        for (unsigned c = 0; c < l->channels; c++)
            fprintf(l->played, ",%.9f", o->amp[c] * STEP_UM);
        for (unsigned c = 0; l->phases && c < l->channels; c++)
            fprintf(l->played, ",%.9f", o->phase[c] * PHASE_STEP_RAD);
        fputc('\n', l->played);
    }
    if (l->plate) {
        fprintf(l->plate, "%.6f,%d", t_s, o->state);
        for (unsigned c = 0; c < l->channels; c++)
            fprintf(l->plate, ",%.9f", o->amp[c] * STEP_UM);
        for (unsigned c = 0; c < l->channels; c++)
            fprintf(l->plate, ",%.9f", plate_um[c]);
        fputc('\n', l->plate);
    }
}

void host_logs_rx(host_logs *l, double t_s, uint32_t frames_ok, uint32_t discarded,
                  double core_t_s)
{
    if (l->rx)
        fprintf(l->rx, "%.6f,%" PRIu32 ",%" PRIu32 ",%.6f\n", t_s, frames_ok, discarded,
                core_t_s);
}

/* Says that the log written to path was lost (reason: an errno value, 0 if unknown). */
static void lose(host_logs *l, const char *path, int reason)
{
    fprintf(stderr,
            "frictex-fw-host: cannot write the log file %s: %s; logging stopped, the device "
            "goes on\n",
            path, strerror(reason ? reason : EIO));
    l->lost = true;
}

/* Flushes the log at *f, and closes it when closing or when the flush was refused (its
 * buffered rows are then dropped): a refusal loses it (lose()). */
static void end_or_flush(host_logs *l, FILE **f, const char *path, bool closing)
{
    if (!*f)
        return;
    errno = 0;
    bool refused = fflush(*f) != 0 || ferror(*f); /* ferror: an earlier fprintf's refusal */
    int reason = errno;
    if (refused || closing) {
        refused = fclose(*f) != 0 || refused;
        reason = reason ? reason : errno;
        *f = NULL;
    }
    if (refused)
        lose(l, path, reason);
}

static void each_log(host_logs *l, bool closing)
{
    end_or_flush(l, &l->played, l->played_path, closing);
    end_or_flush(l, &l->plate, l->plate_path, closing);
    end_or_flush(l, &l->rx, l->rx_path, closing);
}

void host_logs_flush(host_logs *l) { each_log(l, false); }

void host_logs_close(host_logs *l) { each_log(l, true); }
