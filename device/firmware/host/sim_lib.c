/* The host port's core on a virtual clock, as a shared library for Python (ctypes):
 * the same calls as the reference device's DeviceCore (receive bytes at a time, advance
 * the clock to a time), so one test suite can run against both. The caller owns the
 * memory of each instance (fwsim_size() bytes). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../core/device.h"
#include "board.h"
#include "params.h"

typedef struct {
    fw_device dev;
    host_board board;
    double rate_hz;
    uint64_t tick; /* unwrapped */
} fwsim;

size_t fwsim_size(void) { return sizeof(fwsim); }

const char *fwsim_init(fwsim *s, const host_params *p)
{
    fw_config cfg;
    const char *problem = host_params_to_config(p, &cfg);
    if (problem)
        return problem;
    memset(s, 0, sizeof *s);
    fw_init(&s->dev, &cfg, host_board_init(&s->board, p), &s->board);
    s->rate_hz = p->rate_hz;
    return NULL;
}

/* Bytes arriving at t_s; the replies are written to reply (at most cap bytes). */
size_t fwsim_receive(fwsim *s, const uint8_t *data, size_t n, double t_s, uint8_t *reply,
                     size_t cap)
{
    s->board.tx = reply;
    s->board.tx_cap = cap;
    s->board.tx_len = 0;
    fw_receive(&s->dev, data, n, (uint32_t)(uint64_t)(t_s * s->rate_hz));
    s->board.tx = NULL;
    return s->board.tx_len;
}

/* Run ticks up to (not including) floor(t_s * rate), at most max of them, stopping
 * after a tick that left something for fwsim_poll (a Flushed, a ForceReport); per tick it
 * writes the setpoints (channels counts), the plate (channels um), the state, whether a
 * sample was played and its index, and the phases. forces: NULL, or (lateral, normal)
 * counts per tick for the lateral force sensor. Returns the ticks run. */
size_t fwsim_advance(fwsim *s, double t_s, size_t max, uint16_t *setpoint, double *plate,
                     uint8_t *state, uint8_t *played, uint64_t *index, uint16_t *phase,
                     const int16_t *forces)
{
    uint64_t end = (uint64_t)(t_s * s->rate_hz);
    unsigned ch = s->dev.cfg.channels;
    size_t k = 0;
    bool said = false;
    for (; k < max && s->tick < end && !said; k++, s->tick++) {
        s->board.forces_now = forces ? forces + 2 * k : NULL;
        const fw_output *o = fw_tick(&s->dev);
        said = s->dev.flushed_pending || s->dev.force_pending;
        host_board_step(&s->board, o->amp);
        memcpy(setpoint + k * ch, o->amp, 2 * ch);
        memcpy(phase + k * ch, o->phase, 2 * ch);
        memcpy(plate + k * ch, s->board.plate_um, sizeof(double) * ch);
        state[k] = o->state;
        played[k] = o->played;
        index[k] = o->index;
    }
    s->board.forces_now = NULL;
    return k;
}

/* What the device says on its own after the ticks run so far (a Flushed); the bytes are
 * written to out (at most cap). */
size_t fwsim_poll(fwsim *s, uint8_t *out, size_t cap)
{
    s->board.tx = out;
    s->board.tx_cap = cap;
    s->board.tx_len = 0;
    fw_poll(&s->dev);
    s->board.tx = NULL;
    return s->board.tx_len;
}

unsigned fwsim_max_channels(void) { return FW_MAX_CHANNELS; }

/* The state and counters, in this order (device/firmware/ccore.py names them). */
void fwsim_counters(const fwsim *s, uint64_t out[27])
{
    const fw_device *d = &s->dev;
    const fw_rx_counts *c = &d->rx.counts;
    uint64_t v[27] = {
        d->state, d->buf.level, d->play_index, d->play_index + d->end, s->tick,
        d->stopped, fw_finished(d), d->prefill,
        d->k.underruns, d->k.gap_samples, d->k.late_samples, d->k.overflow_samples,
        d->k.watchdog_trips, d->k.clamped, d->k.played_samples,
        d->session.played, d->session.flushed, d->session.flushes,
        c->frames_ok, c->lost_frames, c->crc_errors, c->cobs_errors, c->short_frames,
        c->oversize, c->bad_version, c->unknown_type, c->bad_payload,
    };
    memcpy(out, v, sizeof v);
}
