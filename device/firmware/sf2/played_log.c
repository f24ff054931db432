#include "played_log.h"

#include <string.h>

#include "board.h"

#define RECORD (4u + 2u * BOARD_CHANNELS)
#define LOG_SIZE 16384u /* bytes, a power of two: 270 ms of one-channel records */
#define BATCH_TICKS 20u  /* a batch at least every 2 ms while samples play */

static uint8_t buf[LOG_SIZE];
static volatile uint32_t head, tail; /* head: the interrupt's, tail: the main loop's */
static uint32_t file = UINT32_MAX, last_flush;

/* Semihosting call (ARM DUI 0471): operation in r0, argument block in r1, result in r0. */
static uint32_t semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void played_log_open(void)
{
    static const char name[] = BOARD_PLAYED_LOG;
    const uint32_t open_args[3] = {(uint32_t)name, 5u /* "wb" */, sizeof name - 1u};
    file = semihost(0x01u /* SYS_OPEN */, open_args);
}

bool played_log_note(const fw_output *o)
{
    if (!o->played)
        return true;
    uint32_t h = head;
    if (LOG_SIZE - (h - tail) < RECORD)
        return false;
    uint8_t rec[RECORD];
    uint32_t index = (uint32_t)o->index;
    memcpy(rec, &index, 4);
    memcpy(rec + 4, o->amp, 2 * BOARD_CHANNELS);
    for (unsigned i = 0; i < RECORD; i++)
        buf[(h + i) & (LOG_SIZE - 1u)] = rec[i];
    head = h + RECORD;
    return true;
}

bool played_log_flush(uint32_t now, bool force)
{
    uint32_t h = head, t = tail;
    if (h == t)
        return true;
    if (!force && now - last_flush < BATCH_TICKS && h - t < LOG_SIZE / 2)
        return false;
    while (t != h) { /* at most two pieces: to the ring's end, then from its start */
        uint32_t at = t & (LOG_SIZE - 1u), n = h - t;
        if (n > LOG_SIZE - at)
            n = LOG_SIZE - at;
        const uint32_t write_args[3] = {file, (uint32_t)(buf + at), n};
        semihost(0x05u /* SYS_WRITE */, write_args);
        t += n;
    }
    tail = t;
    last_flush = now;
    return true;
}
