/* Drives the core as the Cortex-M port does (2 channels, 400-sample buffer, no phases):
 * a Hello, then a 50-sample Block and a Heartbeat every 50 ticks, for 100000 ticks of
 * steady playing (BENCH_TICKS). `make isr-cost` runs it under callgrind, counting only inside fw_tick:
 * the per-sample work of the sample interrupt. */
#include <stdio.h>
#include <string.h>

#include "../core/device.h"

#ifndef BENCH_TICKS
#define BENCH_TICKS 100000u
#endif

static fw_device dev;
static void drop(void *ctx, const uint8_t *p, size_t n) { (void)ctx, (void)p, (void)n; }
static const fw_hal hal = {drop, NULL, NULL, NULL, NULL};
static uint8_t frame[512];
static size_t frame_len;

static void collect(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    memcpy(frame + frame_len, p, n);
    frame_len += n;
}

static void send(uint8_t type, uint8_t *body, size_t payload, uint16_t seq, uint32_t now)
{
    frame_len = 0;
    fw_tx_frame(body, payload, 2, type, seq, collect, NULL);
    fw_receive(&dev, frame, frame_len, now);
}

int main(void)
{
    fw_config cfg = {.channels = 2, .rate_mhz = 10000000, .buffer_samples = 400,
                     .watchdog_ms = 25, .ramp_ms = 20, .limits = {16384, 16384},
                     .protocol_version = 2};
    fw_init(&dev, &cfg, &hal, NULL);
    uint8_t body[8 + 12 + 50 * 2 * 2];
    fw_put32(body + 4, 100); /* Hello(prefill 100) */
    send(FW_HELLO, body, 4, 0, 0);
    uint16_t seq = 1;
    uint64_t next = 0;
    unsigned long played = 0;
    for (uint32_t t = 0; t < BENCH_TICKS; t++) {
        if (t % 50 == 0) {
            uint8_t *p = fw_put64(body + 4, next);
            p = fw_put16(p, 50);
            *p++ = 2;
            *p++ = 0;
            for (int i = 0; i < 100; i++)
                p = fw_put16(p, (uint16_t)((t + i) * 37 % 16384));
            send(FW_BLOCK, body, 12 + 200, seq++, t);
            fw_put32(body + 4, t);
            send(FW_HEARTBEAT, body, 4, seq++, t);
            next += 50;
        }
        played += fw_tick(&dev)->played;
    }
    printf("%lu of %u ticks played a sample; %u underruns\n", played, BENCH_TICKS,
           (unsigned)dev.k.underruns);
    return played + 50 >= BENCH_TICKS ? 0 : 1;
}
