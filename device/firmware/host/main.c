/* The host port: the firmware core on a pseudo-terminal and the wall clock, so frictex's
 * link talks to compiled C exactly as to a board (`--device PATH`). Mirrors serve() of
 * device/link/simdevice.py: bytes that arrived are handled before the clock advances,
 * so a process that was descheduled does not mistake its own sleep for host silence. */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "../core/device.h"
#include "board.h"
#include "cli.h"
#include "logs.h"

#define PROG "frictex-fw-host"

static fw_device device; /* static: the core allocates nothing */
static host_board board;
static uint8_t tx[1 << 16];
static volatile sig_atomic_t quit;

static void on_signal(int sig) { quit = sig; }

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* A raw pty: returns the master (non-blocking), keeps the slave open in *slave so the
 * master never reads EIO while no host has the port open. */
static int open_pty(int *slave, const char **path)
{
    int master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) || unlockpt(master) || !(*path = ptsname(master)))
        return -1;
    *slave = open(*path, O_RDWR | O_NOCTTY);
    struct termios t;
    if (*slave < 0 || tcgetattr(*slave, &t))
        return -1;
    cfmakeraw(&t);
    if (tcsetattr(*slave, TCSANOW, &t) || fcntl(master, F_SETFL, O_NONBLOCK))
        return -1;
    return master;
}

int main(int argc, char **argv)
{
    host_cli cli;
    int rc = host_cli_parse(argc, argv, &cli);
    if (rc)
        return rc == 1 ? 0 : 2;
    fw_config cfg;
    const char *problem = host_params_to_config(&cli.params, &cfg);
    if (problem) {
        fprintf(stderr, PROG ": error: %s\n", problem);
        return 2;
    }
    const fw_hal *hal = host_board_init(&board, &cli.params);
    board.tx = tx;
    board.tx_cap = sizeof tx;
    fw_init(&device, &cfg, hal, &board);

    host_logs logs;
    if (!host_logs_open(&logs, cfg.channels, cfg.phases, cli.played_log, cli.plate_log,
                        cli.rx_log)) {
        fprintf(stderr, PROG ": error: cannot open a log file: %s\n", strerror(errno));
        return 2;
    }
    int slave;
    const char *path;
    int master = open_pty(&slave, &path);
    if (master < 0) {
        fprintf(stderr, PROG ": error: cannot open a pseudo-terminal: %s\n", strerror(errno));
        return 1;
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    printf("%s\n", path);
    fflush(stdout);
    fprintf(stderr, PROG ": %u channel(s) at %g Hz on %s; Ctrl-C to quit\n", cfg.channels,
            cli.params.rate_hz, path);

    const double rate = cli.params.rate_hz;
    const double t0 = now_s();
    uint64_t tick = 0; /* the core's clock, unwrapped */
    uint32_t ok = 0, bad = 0;
    while (!quit) {
        struct pollfd pfd = {master, POLLIN, 0};
        int ready = poll(&pfd, 1, 1);
        double t = now_s() - t0;
        uint64_t now_tick = (uint64_t)(t * rate);
        if (ready > 0 && (pfd.revents & POLLIN)) {
            static uint8_t data[65536];
            ssize_t n = read(master, data, sizeof data);
            if (n > 0) {
                board.tx_len = 0;
                fw_receive(&device, data, (size_t)n, (uint32_t)now_tick);
                if (board.tx_len && write(master, tx, board.tx_len) < 0) {
                    /* full or no reader: dropped, as a UART would */
                }
                uint32_t ok2 = device.rx.counts.frames_ok;
                uint32_t bad2 = fw_rx_discarded(&device.rx.counts);
                if (ok2 != ok || bad2 != bad)
                    host_logs_rx(&logs, (now_tick > tick ? now_tick : tick) / rate, ok2, bad2,
                                 tick / rate);
                ok = ok2;
                bad = bad2;
            }
        }
        board.tx_len = 0;
        for (; tick < now_tick; tick++) {
            const fw_output *o = fw_tick(&device);
            host_board_step(&board, o->amp);
            host_logs_tick(&logs, tick / rate, o, board.plate_um);
            fw_poll(&device); /* every report, however many ticks this turn runs */
        }
        if (board.tx_len && write(master, tx, board.tx_len) < 0) {
            /* as above */
        }
        host_logs_flush(&logs);
        if (cli.once && fw_finished(&device))
            break;
        if (cli.parent_pid && getppid() != cli.parent_pid) {
            fprintf(stderr, PROG ": parent process gone; stopping\n");
            break;
        }
    }
    close(master);
    close(slave);
    host_logs_close(&logs);
    fprintf(stderr,
            PROG ": played %" PRIu32 " samples; %" PRIu32 " underruns, %" PRIu32
                 " bad frames, %" PRIu32 " watchdog trips\n",
            device.k.played_samples, device.k.underruns, fw_rx_discarded(&device.rx.counts),
            device.k.watchdog_trips);
    return logs.lost ? 1 : 0; /* said when it was lost */
}
