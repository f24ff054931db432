#include "device.h"

#include <string.h>

static void lock(fw_device *d)
{
    if (d->hal->lock)
        d->hal->lock(d->hal_ctx);
}

static void unlock(fw_device *d)
{
    if (d->hal->unlock)
        d->hal->unlock(d->hal_ctx);
}

/* ceil(ms * rate / 1000) ticks, at least one (integer: a float product would add a tick
 * for 9 ms at 10 kHz). */
static uint32_t ms_to_ticks(uint16_t ms, uint32_t rate_mhz)
{
    uint64_t t = ((uint64_t)ms * rate_mhz + 999999u) / 1000000u;
    return t ? (uint32_t)t : 1u;
}

/* Whether the hold and the ramp, in the whole ticks the device counts, end within the
 * 50 ms stop bound: (ticks(watchdog_ms) + ticks(ramp_ms)) / rate <= 50 ms (PROTOCOL.md
 * 5.3). Rounding up to ticks makes the ms sum alone too weak at low rates. */
static int stop_fits_in_ticks(const fw_config *c)
{
    uint64_t ticks = (uint64_t)ms_to_ticks(c->watchdog_ms, c->rate_mhz) +
                     ms_to_ticks(c->ramp_ms, c->rate_mhz);
    return ticks * 1000000u <= (uint64_t)FW_MAX_STOP_MS * c->rate_mhz;
}

const char *fw_config_check(const fw_config *c)
{
    if (c->channels < 1 || c->channels > FW_MAX_CHANNELS)
        return "channels: expected 1 to FW_MAX_CHANNELS";
    if (c->rate_mhz == 0 || c->rate_mhz >= 4000000000u)
        return "rate: expected (0, 4e6) Hz";
    for (unsigned ch = 0; ch < c->channels; ch++)
        if (c->limits[ch] == 0)
            return "limits: expected at least one count (1/4096 um) per channel";
    if (c->buffer_samples < 2 || (uint64_t)c->buffer_samples * c->channels > FW_STORE_WORDS)
        return "buffer_samples: expected at least 2, and buffer_samples * channels at most "
               "FW_STORE_WORDS";
    if (c->phases && !FW_PHASES)
        return "phases: this build stores no phases (FW_PHASES 0)";
    if (c->watchdog_ms < 1 || c->watchdog_ms > 49)
        return "watchdog_ms: expected 1 to 49";
    if (c->ramp_ms > FW_MAX_STOP_MS - c->watchdog_ms)
        return "ramp_ms: watchdog_ms + ramp_ms must not exceed 50 ms (PROTOCOL.md 5.3)";
    if (c->ramp_ms > 0 && ms_to_ticks(c->ramp_ms, c->rate_mhz) < 2)
        return "ramp_ms: a ramp shorter than 2 ticks at this rate is a step to zero "
               "(PROTOCOL.md 5.3): raise the rate or set ramp_ms 0";
    if (!stop_fits_in_ticks(c))
        return "watchdog_ms, ramp_ms: at this rate their whole ticks exceed 50 ms "
               "(PROTOCOL.md 5.3): raise the rate or shorten them";
    if (c->name && strlen(c->name) > FW_NAME_MAX)
        return "name: longer than FW_NAME_MAX";
    if (c->protocol_version < 1 || c->protocol_version > FW_NEWEST_VERSION)
        return "protocol_version: expected 1 to FW_NEWEST_VERSION";
    return NULL;
}

void fw_init(fw_device *d, const fw_config *cfg, const fw_hal *hal, void *hal_ctx)
{
    memset(d, 0, sizeof *d);
    d->cfg = *cfg;
    d->hal = hal;
    d->hal_ctx = hal_ctx;
    for (unsigned ch = 0; ch < cfg->channels; ch++)
        fw_put16(d->limits_le + 2 * ch, cfg->limits[ch]);
    d->wd_ticks = ms_to_ticks(cfg->watchdog_ms, cfg->rate_mhz);
    d->ramp_ticks = ms_to_ticks(cfg->ramp_ms, cfg->rate_mhz);
    d->missing_ttl = ms_to_ticks(FW_MISSING_TTL_MS, cfg->rate_mhz);
    d->ramp_pos = d->ramp_ticks;
    d->buf.cap = cfg->buffer_samples;
    d->buf.channels = cfg->channels;
    d->prefill = 1;
    d->state = FW_IDLE;
    d->host_version = 1;
    d->force_decimation = cfg->force_decimation ? cfg->force_decimation : 4u;
    fw_rx_init(&d->rx, cfg->protocol_version);
}

/* ------------------------------------------------------------------ replies */

static void write_serial(void *ctx, const uint8_t *p, size_t n)
{
    fw_device *d = ctx;
    if (n)
        d->hal->serial_write(d->hal_ctx, p, n);
}

/* A reply goes out in the version of the frame it answers (PROTOCOL.md 2.1). */
static void send(fw_device *d, uint8_t version, uint8_t type, size_t payload_len)
{
    fw_tx_frame(d->tx, payload_len, version, type, d->tx_seq++, write_serial, d);
}

static void send_info(fw_device *d)
{
    const fw_config *c = &d->cfg;
    fw_info m = {
        .version = c->protocol_version,
        .channels = c->channels,
        .flags = (uint8_t)((c->phases ? FW_FLAG_PHASES : 0u) |
                           (d->hal->amplitude_sensor ? FW_FLAG_SENSOR : 0u) |
                           (d->hal->force_sensor ? FW_FLAG_FORCE : 0u) |
                           (d->hal->force_pair && c->protocol_version >= 3
                                ? FW_FLAG_FORCE_REPORTS
                                : 0u)),
        .rate_mhz = c->rate_mhz,
        .buffer_samples = c->buffer_samples,
        .watchdog_ms = c->watchdog_ms,
        .ramp_ms = c->ramp_ms,
        .limits = d->limits_le,
        .name = (const uint8_t *)(c->name ? c->name : ""),
        .name_len = (uint8_t)(c->name ? strlen(c->name) : 0u),
    };
    send(d, d->host_version, FW_INFO, fw_put_info(d->tx + 4, &m));
}

static void send_status(fw_device *d, uint32_t echo)
{
    uint8_t measured[2 * FW_MAX_CHANNELS];
    fw_status m = {.echo = echo, .measured = measured, .accounted = d->host_version >= 2};
    lock(d);
    m.state = d->state;
    m.play_index = d->play_index;
    m.level = d->buf.level;
    m.buffer_end = d->play_index + d->end;
    m.played = d->session.played;
    m.flushed = d->session.flushed;
    m.flushes = d->session.flushes;
    const uint32_t counters[FW_STATUS_COUNTERS] = {
        d->k.underruns,
        fw_rx_discarded(&d->rx.counts), /* "crc_errors": frames dropped for any reason */
        d->rx.counts.frames_ok,
        d->rx.counts.lost_frames,
        d->k.gap_samples,
        d->k.late_samples,
        d->k.overflow_samples,
        d->k.watchdog_trips,
        d->k.clamped,
    };
    unlock(d);
    memcpy(m.counters, counters, sizeof counters);
    if (d->hal->amplitude_sensor) {
        m.n_measured = d->cfg.channels;
        for (unsigned ch = 0; ch < d->cfg.channels; ch++)
            fw_put16(measured + 2 * ch, d->hal->amplitude_sensor(d->hal_ctx, ch));
    }
    if (d->hal->force_sensor) {
        m.has_force = true;
        m.force_mn = d->hal->force_sensor(d->hal_ctx);
    }
    send(d, d->host_version, FW_STATUS, fw_put_status(d->tx + 4, &m));
}

/* Error texts are for people; they match the reference device's word for word. They are
 * written straight into the reply's payload, where fw_put_error expects them. */
typedef struct {
    uint8_t *s;
    size_t n;
} text;

static text error_text(fw_device *d)
{
    text t = {d->tx + 4 + 7, 0}; /* after the header and code, ref_seq, detail */
    return t;
}

static void add(text *t, const char *s)
{
    while (*s && t->n < FW_ERROR_TEXT_MAX)
        t->s[t->n++] = (uint8_t)*s++;
}

static void add_u32(text *t, uint32_t v)
{
    char digits[10];
    int k = 0;
    do {
        digits[k++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    while (k && t->n < FW_ERROR_TEXT_MAX)
        t->s[t->n++] = (uint8_t)digits[--k];
}

static void send_error(fw_device *d, uint8_t code, uint16_t ref_seq, uint32_t detail,
                       const text *t)
{
    fw_error m = {code, ref_seq, detail, t->s, t->n};
    send(d, d->host_version, FW_ERROR, fw_put_error(d->tx + 4, &m));
}

/* ------------------------------------------------------------------ the clock */

/* Ramp linearly from the current setpoint to zero (5.1, 5.2, 5.3). The ramp steps by
 * from / ramp_ticks, the remainder spread Bresenham-style, so after k ticks the setpoint
 * is from - floor(k * from / ramp_ticks): no division per tick. */
static void begin_ramp(fw_device *d)
{
    d->held = d->wd_ticks + 1u;
    d->ramp_pos = 0;
    for (unsigned ch = 0; ch < d->cfg.channels; ch++) {
        d->ramp_q[ch] = (uint16_t)(d->out.amp[ch] / d->ramp_ticks);
        d->ramp_r[ch] = d->out.amp[ch] % d->ramp_ticks;
        d->ramp_err[ch] = 0;
    }
}

/* Flush, enter SILENT and ramp to zero (5.2, 5.3); a ramp under way goes on. */
static void silence(fw_device *d)
{
    fw_jitter_flush(&d->buf);
    d->end = 0;
    d->state = FW_SILENT;
    if (d->held <= d->wd_ticks)
        begin_ramp(d);
}

static void ramp(fw_device *d)
{
    if (d->ramp_pos >= d->ramp_ticks)
        return;
    d->ramp_pos++;
    for (unsigned ch = 0; ch < d->cfg.channels; ch++) {
        uint16_t fall = d->ramp_q[ch];
        d->ramp_err[ch] += d->ramp_r[ch];
        if (d->ramp_err[ch] >= d->ramp_ticks) {
            d->ramp_err[ch] -= d->ramp_ticks;
            fall++;
        }
        d->out.amp[ch] = (uint16_t)(d->out.amp[ch] - fall);
    }
}

/* 5.1: a BUFFERING or gap tick holds the setpoint, at most wd_ticks since the last sample
 * played; the next begins a ramp to zero (one under way, from a trip or a Hello, goes on). */
static void hold(fw_device *d)
{
    if (d->held < d->wd_ticks) {
        d->held++;
        return;
    }
    if (d->held == d->wd_ticks)
        begin_ramp(d);
    ramp(d);
}

/* A flush that discards what the host sent (a watchdog trip, a Stop without drain):
 * counted in the version 2 accounting; returns the samples discarded. */
static uint32_t count_flush(fw_device *d)
{
    d->session.flushed += d->buf.level;
    d->session.flushes++;
    return d->buf.level;
}

/* 5.1: play the sample due now, or hold across a gap, or run dry; true if the play
 * position advanced. */
static bool play(fw_device *d)
{
    fw_jitter *b = &d->buf;
    if (b->level == 0) { /* hold; play_index stays, so a late host loses nothing */
        if (d->state == FW_DRAINING) {
            silence(d);
            d->stopped = true;
        } else {
            d->k.underruns++;
            d->state = FW_BUFFERING;
        }
        return false;
    }
    uint32_t slot = d->play_slot;
    if (fw_jitter_has(b, slot)) {
        fw_jitter_take(b, slot, d->out.amp, d->out.phase);
        d->out.played = true;
        d->out.index = d->play_index;
        d->k.played_samples++;
        d->session.played++;
        d->held = 0;
    } else {
        d->k.gap_samples++;
        hold(d);
    }
    d->play_index++;
    d->play_slot = slot + 1 == b->cap ? 0 : slot + 1;
    d->end = b->level && d->end ? d->end - 1 : 0;
    return true;
}

/* floor((sum + n / 2) / n): the mean rounded half up, as the reference device does. */
static int16_t mean(int32_t sum, uint16_t n)
{
    int32_t a = sum + n / 2;
    int32_t q = a / n; /* C truncates towards zero ... */
    if (a % n && a < 0)
        q--; /* ... the mean floors */
    return (int16_t)q;
}

/* 4.9: one reading per tick that played (or gapped) sample `index`; a tick that did not
 * advance, or one that played another sample than the next, drops the report being
 * built. A complete report waits for fw_poll (version 3 hosts only). */
static void sense(fw_device *d, bool advanced, uint64_t index)
{
    fw_force_build *f = &d->force;
    if (!advanced) {
        f->open = false;
        return;
    }
    int16_t v[2];
    d->hal->force_pair(d->hal_ctx, v);
    if (!f->open || index != f->next) {
        f->open = true;
        f->start = index;
        f->count = 0;
        f->ticks = 0;
        f->sum[0] = f->sum[1] = 0;
    }
    f->next = index + 1u;
    f->sum[0] += v[0];
    f->sum[1] += v[1];
    if (++f->ticks < d->force_decimation)
        return;
    for (unsigned k = 0; k < 2; k++)
        fw_put16(f->pairs + 4u * f->count + 2u * k, (uint16_t)mean(f->sum[k], f->ticks));
    f->sum[0] = f->sum[1] = 0;
    f->ticks = 0;
    if (++f->count < FW_FORCE_PAIRS)
        return;
    if (d->host_version >= 3) {
        d->force_pending_start = f->start;
        memcpy(d->force_pending_pairs, f->pairs, sizeof f->pairs);
        d->force_version = d->host_version;
        d->force_pending = true;
    }
    f->count = 0;
    f->start += (uint64_t)FW_FORCE_PAIRS * d->force_decimation;
}

const fw_output *fw_tick(fw_device *d)
{
    d->out.played = false;
    if (d->armed && d->state != FW_SILENT &&
        (int32_t)(d->tick - d->last_rx) >= (int32_t)d->wd_ticks) {
        d->k.watchdog_trips++;
        uint32_t flushed = count_flush(d);
        silence(d);
        if (d->host_version >= 2) { /* 5.3: say so (sent by fw_poll) */
            d->flushed = (fw_flushed){FW_FLUSH_WATCHDOG, d->play_index, flushed,
                                      d->session.flushes};
            d->flushed_version = d->host_version;
            d->flushed_pending = true;
        }
    }
    bool advanced = false;
    if (d->state == FW_PLAYING || d->state == FW_DRAINING)
        advanced = play(d);
    if (d->state == FW_SILENT) /* the tick a drain ran dry ramps already */
        ramp(d);
    else if (d->state == FW_BUFFERING) /* as the tick that ran dry holds */
        hold(d);
    if (d->hal->force_pair) /* the sample just played (or gapped) is play_index - 1 */
        sense(d, advanced, d->play_index - advanced);
    d->out.state = d->state;
    d->tick++;
    return &d->out;
}

bool fw_finished(const fw_device *d)
{
    return d->stopped && d->state == FW_SILENT && d->ramp_pos >= d->ramp_ticks;
}

/* ------------------------------------------------------------------ messages */

static void on_hello(fw_device *d, uint32_t prefill)
{
    uint32_t quarter = d->buf.cap / 4u;
    lock(d);
    fw_jitter_flush(&d->buf);
    d->end = 0;
    d->session = (fw_session){0, 0, 0}; /* this flush is not counted */
    d->origin_set = false;
    d->prefill = prefill < 1 ? 1 : prefill;
    if (d->prefill > quarter)
        d->prefill = quarter;
    d->state = FW_BUFFERING;
    if (d->held <= d->wd_ticks) /* 5.1: the flushed stream's setpoint ramps out now */
        begin_ramp(d);
    d->stopped = false;
    d->hello_seen = true;
    unlock(d);
    send_info(d);
}

static void on_heartbeat(fw_device *d, uint32_t token)
{
    lock(d);
    if (d->state == FW_SILENT && !d->stopped)
        d->state = FW_BUFFERING; /* the host is back after a watchdog trip */
    unlock(d);
    send_status(d, token);
}

static void on_stop(fw_device *d, bool drain)
{
    lock(d);
    if (drain && d->buf.level) {
        d->state = FW_DRAINING;
    } else {
        if (!drain) /* 4.6: a drained Stop discards nothing, even on an empty buffer */
            count_flush(d);
        silence(d);
        d->stopped = true;
    }
    unlock(d);
    send_status(d, 0);
}

/* The buffer is empty whenever the play position moves, so the slot of the new
 * position is free to choose. */
static void move_play_position(fw_device *d, uint64_t index)
{
    d->play_index = index;
    d->play_slot = 0;
    d->end = 0;
}

/* Sample numbers wrap modulo 2^64 (PROTOCOL.md 4.3): the offset of `index` from `from`,
 * in [-2^63, 2^63), clamped to +-2^40 (that far out a sample is late or beyond anyway). */
static int64_t offset(uint64_t index, uint64_t from)
{
    const uint64_t far = (uint64_t)1 << 40;
    uint64_t d = index - from;
    bool behind = d >> 63;
    uint64_t magnitude = behind ? ~d + 1 : d;
    if (magnitude > far)
        magnitude = far;
    return behind ? -(int64_t)magnitude : (int64_t)magnitude;
}

/* Whether a block has the device's channels and phases (the configuration never changes). */
static bool block_fits(const fw_device *d, const fw_block *b)
{
    return b->channels == d->cfg.channels && (b->phases != NULL) == d->cfg.phases;
}

/* Answer a block that is not taken: before a Hello or after a completed Stop (not
 * ready), else one of another shape. */
static void refuse_block(fw_device *d, uint16_t seq, const fw_block *b, bool ready)
{
    text t = error_text(d);
    if (!ready) {
        add(&t, "block before Hello");
        send_error(d, FW_NOT_READY, seq, 0, &t);
        return;
    }
    bool phases = b->phases != NULL;
    add(&t, "block has ");
    add_u32(&t, b->channels);
    add(&t, phases ? " channels, phases=True; device has " : " channels, phases=False; device has ");
    add_u32(&t, d->cfg.channels);
    add(&t, d->cfg.phases ? ", phases=True" : ", phases=False");
    send_error(d, FW_BAD_BLOCK, seq, b->channels, &t);
}

/* A block taken (called locked): SILENT after a watchdog trip buffers again, the first
 * block sets the play position, and an empty buffer skips the gap up to the block. */
static void open_block(fw_device *d, const fw_block *b)
{
    if (d->state == FW_SILENT)
        d->state = FW_BUFFERING;
    if (!d->origin_set)
        move_play_position(d, b->start_index);
    int64_t ahead = offset(b->start_index, d->play_index);
    if (d->buf.level == 0 && d->state == FW_BUFFERING && ahead > 0) {
        d->k.gap_samples += (uint32_t)(b->start_index - d->play_index);
        move_play_position(d, b->start_index);
    }
    d->origin_set = true;
}

/* 4.3, steps 1-6. */
static void on_block(fw_device *d, uint16_t seq, const fw_block *b)
{
    unsigned ch = d->cfg.channels;
    bool fits = block_fits(d, b);
    /* Readiness is read in the same locked section that leaves SILENT: a drain running dry
     * in the sample interrupt sets stopped, and no block may restart the plate after it. */
    lock(d);
    bool ready = d->hello_seen && !d->stopped;
    if (ready && fits)
        open_block(d, b);
    unlock(d);
    if (!ready || !fits) {
        refuse_block(d, seq, b, ready);
        return;
    }

    uint32_t late = 0, beyond = 0, clamped = 0;
    for (uint32_t i = 0; i < b->n; i++) {
        uint16_t amp[FW_MAX_CHANNELS], phase[FW_MAX_CHANNELS];
        for (unsigned c = 0; c < ch; c++) {
            amp[c] = fw_le16(b->amps + 2u * (i * ch + c));
            if (amp[c] > d->cfg.limits[c]) { /* the host must clamp; the device checks */
                amp[c] = d->cfg.limits[c];
                clamped++;
            }
            if (b->phases)
                phase[c] = fw_le16(b->phases + 2u * (i * ch + c));
        }
        lock(d); /* the sample clock may have moved on since the last sample */
        int64_t rel = offset(b->start_index + i, d->play_index);
        if (rel < 0) {
            late++;
        } else if (rel >= d->buf.cap) {
            beyond++;
        } else {
            uint32_t slot = d->play_slot + (uint32_t)rel;
            if (slot >= d->buf.cap)
                slot -= d->buf.cap;
            fw_jitter_put(&d->buf, slot, amp, b->phases ? phase : NULL);
            if ((uint32_t)rel >= d->end)
                d->end = (uint32_t)rel + 1;
        }
        unlock(d);
    }
    lock(d);
    d->k.clamped += clamped;
    d->k.late_samples += late;
    d->k.overflow_samples += beyond;
    if (d->state == FW_BUFFERING && d->buf.level >= d->prefill)
        d->state = FW_PLAYING;
    if (d->stopped && d->buf.level) { /* a drain ran dry between two samples: the Stop is */
        count_flush(d);               /* complete, and what was stored after it is flushed */
        fw_jitter_flush(&d->buf);
        d->end = 0;
    }
    unlock(d);

    text t = error_text(d);
    if (beyond) {
        add_u32(&t, beyond);
        add(&t, " samples beyond the buffer");
        send_error(d, FW_OVERFLOW, seq, beyond, &t);
    } else if (late) {
        add_u32(&t, late);
        add(&t, " samples arrived after their time");
        send_error(d, FW_LATE, seq, late, &t);
    }
}

void fw_poll(fw_device *d)
{
    lock(d);
    bool pending = d->flushed_pending;
    fw_flushed m = d->flushed;
    uint8_t version = d->flushed_version;
    d->flushed_pending = false;
    bool forces = d->force_pending;
    uint8_t pairs[sizeof d->force_pending_pairs];
    fw_force f = {d->force_pending_start, d->force_decimation, FW_FORCE_PAIRS, pairs};
    uint8_t force_version = d->force_version;
    if (forces)
        memcpy(pairs, d->force_pending_pairs, sizeof pairs);
    d->force_pending = false;
    unlock(d);
    if (pending)
        send(d, version, FW_FLUSHED, fw_put_flushed(d->tx + 4, &m));
    if (forces)
        send(d, force_version, FW_FORCE, fw_put_force(d->tx + 4, &f));
}

/* ------------------------------------------------------------------ repair (4.10) */
/* Where seq is in the missing list; n_missing if it is not there. */
static uint8_t find_missing(const fw_device *d, uint16_t seq)
{
    uint8_t i = 0;
    while (i < d->n_missing && d->missing_seq[i] != seq)
        i++;
    return i;
}

/* The `lost` host frames just before `seq` are missing since `now`; the newest
 * FW_MISSING_MAX are kept. A number already listed keeps its place and only takes the
 * new tick (as the reference device's dict does), so none is listed twice. Touched only
 * from fw_receive (never from fw_tick). */
static void note_missing(fw_device *d, uint16_t seq, uint16_t lost, uint32_t now)
{
    for (uint16_t k = lost < FW_MISSING_MAX ? lost : FW_MISSING_MAX; k > 0; k--) {
        uint16_t gone = (uint16_t)(seq - k);
        uint8_t at = find_missing(d, gone);
        if (at < d->n_missing) {
            d->missing_tick[at] = now;
            continue;
        }
        if (d->n_missing == FW_MISSING_MAX) { /* forget the oldest */
            memmove(d->missing_seq, d->missing_seq + 1, (FW_MISSING_MAX - 1u) * 2u);
            memmove(d->missing_tick, d->missing_tick + 1, (FW_MISSING_MAX - 1u) * 4u);
            d->n_missing--;
        }
        d->missing_seq[d->n_missing] = gone;
        d->missing_tick[d->n_missing++] = now;
    }
}

/* Remove seq from the missing list; whether it was there. */
static bool take_missing(fw_device *d, uint16_t seq)
{
    uint8_t i = find_missing(d, seq);
    if (i == d->n_missing)
        return false;
    d->n_missing--;
    memmove(d->missing_seq + i, d->missing_seq + i + 1, (size_t)(d->n_missing - i) * 2u);
    memmove(d->missing_tick + i, d->missing_tick + i + 1, (size_t)(d->n_missing - i) * 4u);
    return true;
}

/* Forget what has been missing longer than missing_ttl; send Missing for the rest. */
static void report_missing(fw_device *d, uint32_t now)
{
    uint8_t kept = 0;
    for (uint8_t i = 0; i < d->n_missing; i++)
        if (now - d->missing_tick[i] <= d->missing_ttl) {
            d->missing_seq[kept] = d->missing_seq[i];
            d->missing_tick[kept++] = d->missing_tick[i];
        }
    d->n_missing = kept;
    if (kept)
        send(d, d->host_version, FW_MISSING, fw_put_missing(d->tx + 4, d->missing_seq, kept));
}

static void on_frame(fw_device *d, const fw_msg *msg, uint32_t now_tick)
{
    if (msg->type >= FW_DEVICE_TYPES)
        return; /* 5.3: our own frames echoed back neither arm nor feed the watchdog */
    fw_poll(d); /* a trip noted before this frame is reported before its answer */
    lock(d);
    d->last_rx = (int32_t)(now_tick - d->tick) > 0 ? now_tick : d->tick;
    uint32_t now = d->last_rx;
    d->armed = true; /* 5.3: armed by the first valid frame */
    d->host_version = msg->version;
    unlock(d);
    bool gap = msg->lost && msg->version >= 4;
    if (msg->type == FW_HELLO)
        d->n_missing = 0;
    else if (gap)
        note_missing(d, msg->seq, msg->lost, now);
    switch (msg->type) {
    case FW_HELLO:
        on_hello(d, msg->m.prefill);
        break;
    case FW_RESEND:
        if (take_missing(d, msg->orig_seq)) /* else a duplicate: no effect */
            on_block(d, msg->seq, &msg->m.block);
        break;
    case FW_HEARTBEAT:
        on_heartbeat(d, msg->m.token);
        break;
    case FW_STOP:
        on_stop(d, msg->m.drain);
        break;
    case FW_BLOCK:
        on_block(d, msg->seq, &msg->m.block);
        break;
    default:
        break;
    }
    if (msg->version >= 4 && (gap || msg->type == FW_HEARTBEAT))
        report_missing(d, now);
}

void fw_receive(fw_device *d, const uint8_t *data, size_t n, uint32_t now_tick)
{
    fw_msg msg;
    for (size_t i = 0; i < n; i++)
        if (fw_rx_byte(&d->rx, data[i], &msg))
            on_frame(d, &msg, now_tick);
}
