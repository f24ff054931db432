/* Fuzz target for the receive path and the state machine (libFuzzer entry point; see
 * fuzz_loop.c for a driver without libFuzzer).
 *
 * Input: byte 0 picks the mode and the device (bit 7: "framed" mode; bits 0-1: channels - 1;
 * bit 2: phases; bit 3: speak version 1 only), byte 1 the buffer size, the rest the
 * traffic.
 *   raw mode:    the rest is the byte stream itself, cut at every 0x00. A reference
 *                decoder written here (bitwise CRC, plain COBS) judges each frame; a frame
 *                that fails its CRC or framing must leave the device exactly as it was
 *                (PROTOCOL.md 2: "A dropped frame MUST have no effect at all") and must
 *                not be answered.
 *   framed mode: the rest is [len:u16][ticks:u8][body] records; the harness appends a
 *                correct CRC and stuffs each body, so payloads reach the parser and the
 *                state machine.
 * In both modes the clock runs between frames and every tick is checked: setpoints
 * within the limits, the buffer level equal to the slots marked full. Any out-of-bounds
 * access or undefined behaviour is caught by the sanitizers. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../core/device.h"

static fw_device dev, before;
static size_t replies;

static void serial_write(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    (void)p;
    replies += n;
}

static uint16_t sensor(void *ctx, unsigned ch)
{
    (void)ctx;
    return (uint16_t)(ch * 1000u);
}

static uint16_t force(void *ctx)
{
    (void)ctx;
    return 750;
}

static uint32_t now;

static void force_pair(void *ctx, int16_t out[2])
{
    (void)ctx;
    out[0] = (int16_t)(uint16_t)(now * 7919u); /* the whole i16 range, tick by tick */
    out[1] = (int16_t)(uint16_t)(now * 31u);
}

static const fw_hal hal = {serial_write, sensor, force, NULL, NULL, force_pair};

#define CHECK(cond)                                                                           \
    do {                                                                                      \
        if (!(cond))                                                                          \
            abort();                                                                          \
    } while (0)

static uint32_t ref_crc(const uint8_t *p, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

/* Reference COBS decode of one frame's stuffed bytes; -1 if malformed. */
static long ref_cobs(const uint8_t *in, size_t n, uint8_t *out)
{
    size_t i = 0, k = 0;
    while (i < n) {
        size_t code = in[i], end = i + code;
        if (code == 0 || end > n)
            return -1;
        memcpy(out + k, in + i + 1, code - 1);
        k += code - 1;
        if (code < 255 && end < n)
            out[k++] = 0;
        i = end;
    }
    return (long)k;
}

static bool ref_valid(const uint8_t *stuffed, size_t n)
{
    static uint8_t body[FW_MAX_STUFFED];
    if (n == 0 || n > FW_MAX_STUFFED)
        return false;
    long len = ref_cobs(stuffed, n, body);
    return len >= 8 && ref_crc(body, (size_t)len - 4) == fw_le32(body + len - 4);
}

static void tick_and_check(unsigned ticks)
{
    for (unsigned t = 0; t < ticks; t++, now++) {
        const fw_output *o = fw_tick(&dev);
        fw_poll(&dev);
        for (unsigned c = 0; c < dev.cfg.channels; c++)
            CHECK(o->amp[c] <= dev.cfg.limits[c]);
        CHECK(o->state <= FW_SILENT);
    }
    uint32_t full = 0;
    for (uint32_t s = 0; s < dev.buf.cap; s++)
        full += fw_jitter_has(&dev.buf, s);
    CHECK(full == dev.buf.level && dev.buf.level <= dev.buf.cap);
}

/* Everything but the receiver's own state (which a dropped frame does reset). */
static bool unchanged(void)
{
    size_t at = offsetof(fw_device, rx), end = at + sizeof dev.rx;
    return !memcmp(&dev, &before, at) &&
           !memcmp((char *)&dev + end, (char *)&before + end, sizeof dev - end);
}

static void feed_checked(const uint8_t *p, size_t n, bool delimited)
{
    bool valid = delimited && ref_valid(p, n);
    memcpy(&before, &dev, sizeof dev);
    size_t sent = replies;
    fw_receive(&dev, p, n + delimited, now);
    if (!valid)
        CHECK(unchanged() && replies == sent);
}

static void raw_mode(const uint8_t *p, size_t n)
{
    size_t start = 0;
    for (size_t i = 0; i <= n; i++) {
        if (i == n || p[i] == 0) {
            feed_checked(p + start, i - start, i < n);
            tick_and_check((unsigned)((i - start) % 97u));
            start = i + 1;
        }
    }
}

static void stuff_and_feed(const uint8_t *body, size_t n)
{
    static uint8_t framed[FW_MAX_STUFFED + 64], scratch[FW_MAX_BODY];
    memcpy(scratch, body, n);
    fw_put32(scratch + n, ref_crc(scratch, n));
    n += 4;
    size_t k = 0, code_at = k++;
    uint8_t code = 1;
    for (size_t i = 0; i < n; i++) {
        if (scratch[i] == 0) {
            framed[code_at] = code;
            code_at = k++;
            code = 1;
        } else {
            framed[k++] = scratch[i];
            if (++code == 255) {
                framed[code_at] = code;
                code_at = k++;
                code = 1;
            }
        }
    }
    framed[code_at] = code;
    framed[k++] = 0;
    fw_receive(&dev, framed, k, now);
}

static void framed_mode(const uint8_t *p, size_t n)
{
    while (n >= 3) {
        size_t len = fw_le16(p);
        unsigned ticks = p[2] * 4u;
        p += 3;
        n -= 3;
        if (len > n)
            len = n;
        stuff_and_feed(p, len > FW_MAX_BODY - 4 ? FW_MAX_BODY - 4 : len);
        tick_and_check(ticks);
        p += len;
        n -= len;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2)
        return 0;
    fw_config cfg = {
        .channels = (uint8_t)(1 + (data[0] & 3)),
        .phases = (data[0] & 4) != 0,
        .rate_mhz = 10000000,
        .watchdog_ms = 25,
        .ramp_ms = 20,
        .name = "fuzz",
        .protocol_version = (data[0] & 8) ? 1 : FW_NEWEST_VERSION,
    };
    cfg.buffer_samples = 2 + data[1] % (FW_STORE_WORDS / cfg.channels - 1);
    for (unsigned c = 0; c < cfg.channels; c++)
        cfg.limits[c] = (uint16_t)(4096 * (c + 1));
    CHECK(fw_config_check(&cfg) == NULL);
    fw_init(&dev, &cfg, &hal, NULL);
    now = 0;
    if (data[0] & 0x80)
        framed_mode(data + 2, size - 2);
    else
        raw_mode(data + 2, size - 2);
    return 0;
}
