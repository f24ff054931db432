/* The device side of PROTOCOL.md: handshake, jitter buffer, playing, stopping, the
 * watchdog and the reports. Portable C99, no allocation: a port owns one fw_device
 * (static storage), feeds it received bytes and calls fw_tick() at the sample rate. */
#ifndef FW_DEVICE_H
#define FW_DEVICE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fw_limits.h"
#include "hal.h"
#include "jitter.h"
#include "rx.h"
#include "tx.h"
#include "wire.h"

typedef struct {
    uint8_t channels;
    bool phases; /* accepts a phase per channel (needs FW_PHASES) */
    uint32_t rate_mhz;
    uint32_t buffer_samples;
    uint16_t watchdog_ms, ramp_ms;
    uint16_t limits[FW_MAX_CHANNELS]; /* amplitude limit per channel, counts */
    const char *name;
    uint8_t protocol_version; /* newest version spoken, 1 to FW_NEWEST_VERSION */
    uint16_t force_decimation; /* ticks per ForceReport value (4.9); 0: 4 */
} fw_config;

/* What one tick produced: the setpoints to put on the outputs now. */
typedef struct {
    uint16_t amp[FW_MAX_CHANNELS];   /* counts of 1/4096 um */
    uint16_t phase[FW_MAX_CHANNELS]; /* counts of 2 pi / 65536 */
    uint8_t state;
    bool played;    /* a sample left the buffer this tick ... */
    uint64_t index; /* ... and this was its number */
} fw_output;

/* Cumulative since power-up (Status version 1 counters, and played_samples). */
typedef struct {
    uint32_t underruns, gap_samples, late_samples, overflow_samples, watchdog_trips, clamped,
        played_samples;
} fw_counters;

/* Since the last Hello (Status version 2 accounting, PROTOCOL.md 4.6). */
typedef struct {
    uint32_t played, flushed, flushes;
} fw_session;

/* Largest payload the device sends: an Error with its longest text, a Status with every
 * channel measured, or an Info with the longest name (PROTOCOL.md 4.2, 4.6, 4.7). */
#define FW_BIGGER(a, b) ((a) > (b) ? (a) : (b))
/* how long a missing host frame is asked for (ms, PROTOCOL.md 4.10) */
#define FW_MISSING_TTL_MS 100u
/* the plate is still within this many ms of the host falling silent (PROTOCOL.md 5.3) */
#define FW_MAX_STOP_MS 50u
#define FW_TX_PAYLOAD_MAX                                                                     \
    FW_BIGGER(FW_BIGGER(7u + FW_ERROR_TEXT_MAX, 11u + 4u * FW_FORCE_PAIRS),                   \
              FW_BIGGER(80u + 2u * FW_MAX_CHANNELS, 16u + 2u * FW_MAX_CHANNELS + FW_NAME_MAX))

/* The ForceReport being built from the force_pair hook (PROTOCOL.md 4.9). */
typedef struct {
    bool open;               /* a report is being built from sample start ... */
    uint64_t start, next;    /* ... and the next tick must play sample next to go on */
    int32_t sum[2];          /* lateral, normal counts of the current value */
    uint16_t ticks;          /* ticks summed into it */
    uint8_t count;           /* values complete */
    uint8_t pairs[4u * FW_FORCE_PAIRS];
} fw_force_build;

typedef struct {
    fw_config cfg;
    const fw_hal *hal;
    void *hal_ctx;
    uint8_t limits_le[2 * FW_MAX_CHANNELS];
    uint32_t wd_ticks, ramp_ticks;
    fw_rx rx;
    fw_jitter buf;
    uint8_t state;
    bool hello_seen, origin_set, stopped, armed;
    uint32_t prefill;
    uint64_t play_index;
    uint32_t play_slot; /* slot of play_index */
    uint32_t end;       /* one past the furthest sample held, relative to play_index */
    uint32_t tick;      /* ticks since power-up, wrapping */
    uint32_t last_rx;   /* tick of the last valid frame */
    uint16_t tx_seq;
    uint8_t host_version; /* of the last valid frame: replies and Flushed use it */
    fw_counters k;
    fw_session session;
    bool flushed_pending; /* a watchdog trip to report (fw_poll sends it) */
    uint8_t flushed_version;
    fw_flushed flushed;
    uint16_t force_decimation;
    fw_force_build force;
    bool force_pending; /* a complete report to send (fw_poll sends it; a newer replaces it) */
    uint8_t force_version;
    uint64_t force_pending_start;
    uint8_t force_pending_pairs[4u * FW_FORCE_PAIRS];
    uint32_t held;     /* BUFFERING ticks held since the last sample played; wd_ticks + 1:
                          a ramp to zero has begun since (PROTOCOL.md 5.1) */
    uint32_t ramp_pos;                   /* ticks into the ramp to zero */
    uint16_t ramp_q[FW_MAX_CHANNELS];    /* per tick the ramp falls by q ... */
    uint32_t ramp_r[FW_MAX_CHANNELS];    /* ... plus r / ramp_ticks (accumulated in err) */
    uint32_t ramp_err[FW_MAX_CHANNELS];
    uint16_t missing_seq[FW_MISSING_MAX];  /* host frames found missing, oldest first */
    uint32_t missing_tick[FW_MISSING_MAX]; /* ... and the tick each was found (4.10) */
    uint8_t n_missing;
    uint32_t missing_ttl;                  /* ticks a missing frame stays asked for */
    fw_output out;
    uint8_t tx[FW_TX_OVERHEAD + FW_TX_PAYLOAD_MAX];
} fw_device;

/* NULL if the configuration is usable, else what is wrong with it. */
const char *fw_config_check(const fw_config *cfg);

/* Power-up state (IDLE, output zero). cfg must pass fw_config_check. */
void fw_init(fw_device *d, const fw_config *cfg, const fw_hal *hal, void *hal_ctx);

/* Bytes from the host; now_tick is the port's clock in ticks (PROTOCOL.md 5.3: the frame
 * arrived now). Replies go out through hal->serial_write. */
void fw_receive(fw_device *d, const uint8_t *data, size_t n, uint32_t now_tick);

/* Send what the device says on its own: a Flushed after a watchdog trip (PROTOCOL.md 4.8),
 * then a ForceReport (4.9). fw_tick() only notes them (it may run in an interrupt): call
 * this from the main loop after ticks, at least once per report (FW_FORCE_PAIRS *
 * force_decimation ticks), or a newer report replaces the one waiting. fw_receive calls
 * it before answering a frame, so it is never late. */
void fw_poll(fw_device *d);

/* One tick of the sample clock (PROTOCOL.md 5): returns the setpoints for the outputs. */
const fw_output *fw_tick(fw_device *d);

/* A Stop has completed and the output has ramped to zero. */
bool fw_finished(const fw_device *d);

#endif
