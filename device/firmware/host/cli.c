#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "frictex-fw-host"

static const char usage[] =
    "usage: " PROG " [--channels N] [--rate HZ] [--limit UM]... [--buffer N]\n"
    "       [--bandwidth HZ] [--watchdog-ms MS] [--ramp-ms MS] [--phases] [--sensor]\n"
    "       [--force N] [--lateral N] [--log CSV] [--plate-log CSV] [--rx-log CSV]\n"
    "       [--protocol {1,2,3,4}]\n"
    "       [--once]\n"
    "\n"
    "The frictex reference firmware's core on a pseudo-terminal: prints the pty's path as\n"
    "the first line on stdout, then speaks the device side of device/PROTOCOL.md to host\n"
    "after host until SIGINT/SIGTERM. The flags of `frictex sim-device` (but --tcp).\n"
    "\n"
    "  --channels N      actuator channels (default 1)\n"
    "  --rate HZ         sample rate the device plays at (default 10000 Hz)\n"
    "  --limit UM        amplitude limit in um zero-to-peak, declared to the host; once for\n"
    "                    all channels or once per channel (default 4.0)\n"
    "  --buffer N        jitter-buffer capacity in samples (default 4096)\n"
    "  --bandwidth HZ    corner frequency of the modelled amplitude loop, a first-order\n"
    "                    low pass (default 400 Hz); -3 dB there only where it is well\n"
    "                    under --rate (PROTOCOL.md 5.4)\n"
    "  --watchdog-ms MS  host silence that trips the watchdog (default 25 ms)\n"
    "  --ramp-ms MS      ramp to zero after a trip or a stop (default 20 ms)\n"
    "  --phases          accept a phase per channel\n"
    "  --sensor          report the modelled plate amplitude as 'measured'\n"
    "  --force N         report this normal force (N) from a simulated force sensor\n"
    "  --lateral N       send ForceReports (protocol 3) of this lateral force (N) and the\n"
    "                    --force normal force (0 without), 4 samples a value, 10 a report\n"
    "  --log CSV         write every played sample: index,ch0_um,...\n"
    "  --plate-log CSV   write every tick: t_s,state,ch<k>_setpoint_um,ch<k>_plate_um\n"
    "  --rx-log CSV      write t_s,frames_ok,discarded,core_t_s whenever a read changed\n"
    "                    the counts (core_t_s: how far the clock had played by then)\n"
    "  --protocol V      newest protocol version to speak (default 4; 1 to 3 act as\n"
    "                    firmware of that version)\n"
    "  --once            exit once the first host's Stop has played out\n";

/* Flags that take a value, each between spaces (see flag_key). */
static const char valued[] = " --channels --rate --limit --buffer --bandwidth --watchdog-ms "
                             "--ramp-ms --force --lateral --log --plate-log --rx-log --protocol "
                             "--parent-pid ";

static const char *flag_key(const char *flag)
{
    static char key[40];
    snprintf(key, sizeof key, " %.36s ", flag);
    return key;
}

static int bad(const char *flag, const char *value, const char *expected)
{
    fprintf(stderr, PROG ": error: argument %s: invalid value '%s' (expected %s)\n", flag,
            value, expected);
    return 2;
}

/* An integer of at least `least` (0 or 1). */
static int integer(const char *flag, const char *s, unsigned long *out, long least)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *s == '\0' || *end != '\0' || v < least)
        return bad(flag, s, least > 0 ? "a positive integer" : "an integer >= 0");
    *out = (unsigned long)v;
    return 0;
}

static int number(const char *flag, const char *s, double *out, int positive)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || *s == '\0' || *end != '\0' || v != v || (positive && !(v > 0)))
        return bad(flag, s, positive ? "a positive number" : "a number");
    *out = v;
    return 0;
}

int host_cli_parse(int argc, char **argv, host_cli *out)
{
    *out = (host_cli){0};
    host_params *p = &out->params;
    host_params_default(p);
    int limits = 0;
    for (int i = 1; i < argc; i++) {
        char *flag = argv[i];
        char *value = strchr(flag, '=');
        if (value && strncmp(flag, "--", 2) == 0)
            *value++ = '\0';
        int is_switch = !strcmp(flag, "--phases") || !strcmp(flag, "--sensor") ||
                        !strcmp(flag, "--once") || !strcmp(flag, "--help") ||
                        !strcmp(flag, "-h");
        if (!is_switch && !strstr(valued, flag_key(flag))) {
            fprintf(stderr, PROG ": error: unrecognized argument: %s\n%s", flag, usage);
            return 2;
        }
        if (!is_switch && !value) {
            if (i + 1 >= argc) {
                fprintf(stderr, PROG ": error: argument %s: expected one argument\n%s", flag,
                        usage);
                return 2;
            }
            value = argv[++i];
        }
        unsigned long pid;
        int rc = 0;
        if (!strcmp(flag, "--help") || !strcmp(flag, "-h")) {
            fputs(usage, stdout);
            return 1;
        } else if (!strcmp(flag, "--phases")) {
            p->phases = true;
        } else if (!strcmp(flag, "--sensor")) {
            p->sensor = true;
        } else if (!strcmp(flag, "--once")) {
            out->once = true;
        } else if (!strcmp(flag, "--protocol")) {
            rc = integer(flag, value, &p->protocol_version, 1);
        } else if (!strcmp(flag, "--channels")) {
            rc = integer(flag, value, &p->channels, 1);
        } else if (!strcmp(flag, "--rate")) {
            rc = number(flag, value, &p->rate_hz, 1);
        } else if (!strcmp(flag, "--limit")) {
            if (limits == FW_MAX_CHANNELS)
                return bad(flag, value, "at most one --limit per channel");
            rc = number(flag, value, &p->limits_um[limits++], 1);
            p->n_limits = (unsigned)limits;
        } else if (!strcmp(flag, "--buffer")) {
            rc = integer(flag, value, &p->buffer_samples, 1);
        } else if (!strcmp(flag, "--bandwidth")) {
            rc = number(flag, value, &p->bandwidth_hz, 1);
        } else if (!strcmp(flag, "--watchdog-ms")) {
            rc = integer(flag, value, &p->watchdog_ms, 1);
        } else if (!strcmp(flag, "--ramp-ms")) {
            rc = integer(flag, value, &p->ramp_ms, 0);
        } else if (!strcmp(flag, "--force")) {
            rc = number(flag, value, &p->force_n, 0);
            p->has_force = true;
        } else if (!strcmp(flag, "--lateral")) {
            rc = number(flag, value, &p->lateral_n, 0);
            p->has_lateral = true;
        } else if (!strcmp(flag, "--log")) {
            out->played_log = value;
        } else if (!strcmp(flag, "--plate-log")) {
            out->plate_log = value;
        } else if (!strcmp(flag, "--rx-log")) {
            out->rx_log = value;
        } else if (!strcmp(flag, "--parent-pid")) {
            rc = integer(flag, value, &pid, 1);
            out->parent_pid = (long)pid;
        }
        if (rc)
            return rc;
    }
    return 0;
}
