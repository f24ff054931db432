/* The C core with a lock hook that runs the sample interrupt (one fw_tick) just before
 * the k-th critical section of a frame, for k = 0, 1, ... until the frame takes fewer
 * locks: every point at which the interrupt can preempt fw_receive. Built and driven by
 * tests/test_firmware_lock_race.py.
 *
 * stdin: two lines of hex bytes, the setup (fed at once) and the racing frame. Before the
 * racing frame the device plays until its buffer is empty (a drain then runs dry on the
 * next tick). One line per k on stdout:
 *   k <k> played_after_stop <n> restarted <n> held_after_stop <n> flushed <n> replies <hex>
 * played_after_stop: samples played on ticks that began with the Stop completed;
 * restarted: checks (after the frame, after each tick) that found stopped set outside
 * SILENT; held_after_stop: the buffer's level once the Stop completed and the ticks ran;
 * flushed: the session's flushed samples. The ticks after the frame: TICKS_AFTER, each
 * fed no frame. */
#include <stdio.h>
#include <string.h>

#include "device.h"

#define TICKS_AFTER 300u
#define MAX_BYTES 20000u

static fw_device dev;
static long lock_at = -1, locks;
static unsigned played_after_stop, restarted;
static uint8_t replies[MAX_BYTES];
static size_t n_replies;

static void check_stopped(void)
{
    if (dev.stopped && dev.state != FW_SILENT)
        restarted++;
}

static void tick(void)
{
    bool was_stopped = dev.stopped;
    const fw_output *o = fw_tick(&dev);
    if (was_stopped && o->played)
        played_after_stop++;
    check_stopped();
}

static void on_lock(void *ctx)
{
    (void)ctx;
    if (locks++ == lock_at)
        tick();
}

static void on_unlock(void *ctx) { (void)ctx; }

static void on_write(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    if (n_replies + n <= MAX_BYTES) {
        memcpy(replies + n_replies, p, n);
        n_replies += n;
    }
}

static const fw_hal hal = {.serial_write = on_write, .lock = on_lock, .unlock = on_unlock};

static int hex_value(int c)
{
    const char *digits = "0123456789abcdef";
    const char *at = c > 0 ? strchr(digits, c) : NULL;
    return at ? (int)(at - digits) : -1;
}

/* One line of hex digits (lower case); the bytes read. */
static size_t read_hex(uint8_t *out)
{
    size_t n = 0;
    int hi, lo;
    while (n < MAX_BYTES && (hi = hex_value(getchar())) >= 0 && (lo = hex_value(getchar())) >= 0)
        out[n++] = (uint8_t)(hi << 4 | lo);
    return n;
}

int main(void)
{
    static uint8_t setup[MAX_BYTES], race[MAX_BYTES];
    size_t n_setup = read_hex(setup), n_race = read_hex(race);
    fw_config cfg = {.channels = 1, .rate_mhz = 10000000, .buffer_samples = 4096,
                     .watchdog_ms = 25, .ramp_ms = 20, .limits = {16384}, .name = "race",
                     .protocol_version = FW_NEWEST_VERSION};
    const char *problem = fw_config_check(&cfg);
    if (problem || !n_setup || !n_race) {
        fprintf(stderr, "lock race: %s\n", problem ? problem : "expected two lines of hex");
        return 2;
    }
    for (long k = 0;; k++) {
        fw_init(&dev, &cfg, &hal, NULL);
        lock_at = -1;
        fw_receive(&dev, setup, n_setup, dev.tick);
        while (dev.buf.level)
            fw_tick(&dev);
        played_after_stop = restarted = 0;
        n_replies = 0;
        locks = 0;
        lock_at = k;
        fw_receive(&dev, race, n_race, dev.tick);
        if (locks <= k)
            return 0; /* the interrupt fired at no lock: every point was tried */
        lock_at = -1;
        check_stopped();
        for (unsigned t = 0; t < TICKS_AFTER; t++)
            tick();
        printf("k %ld played_after_stop %u restarted %u held_after_stop %u flushed %u replies ",
               k, played_after_stop, restarted, dev.stopped ? (unsigned)dev.buf.level : 0u,
               (unsigned)dev.session.flushed);
        for (size_t i = 0; i < n_replies; i++)
            printf("%02x", replies[i]);
        printf("\n");
    }
}
