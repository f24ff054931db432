#include "board.h"

#include <math.h>
#include <string.h>

#define STEP_UM (1.0 / 4096.0)

static void serial_write(void *ctx, const uint8_t *p, size_t n)
{
    host_board *b = ctx;
    if (n > b->tx_cap - b->tx_len)
        n = b->tx_cap - b->tx_len; /* a full queue drops, as a UART would */
    memcpy(b->tx + b->tx_len, p, n);
    b->tx_len += n;
}

/* The wire's rounding of an amplitude: nearest count in [0, 65535]. */
static uint16_t plate_sensor(void *ctx, unsigned ch)
{
    double counts = nearbyint(((host_board *)ctx)->plate_um[ch] / STEP_UM);
    if (!(counts > 0))
        return 0;
    return counts > 65535 ? 65535 : (uint16_t)counts;
}

static uint16_t force_sensor(void *ctx) { return ((host_board *)ctx)->force_mn; }

static void force_pair(void *ctx, int16_t out[2])
{
    const host_board *b = ctx;
    const int16_t *v = b->forces_now ? b->forces_now : b->forces;
    out[0] = v[0];
    out[1] = v[1];
}

/* N to counts of 1/4096 N, nearest, within int16 (the wire's force_to_wire). */
static int16_t force_counts(double n)
{
    double c = nearbyint(n * 4096.0);
    return (int16_t)(c > 32767 ? 32767 : c < -32768 ? -32768 : c);
}

const fw_hal *host_board_init(host_board *b, const host_params *p)
{
    memset(b, 0, sizeof *b);
    /* PROTOCOL.md 5.4: the first-order loop held over each tick, discretised exactly */
    b->pole = exp(-2.0 * M_PI * p->bandwidth_hz / p->rate_hz);
    b->channels = (unsigned)p->channels;
    b->force_mn = p->has_force ? (uint16_t)nearbyint(p->force_n * 1000.0) : 0;
    b->forces[0] = force_counts(p->lateral_n);
    b->forces[1] = force_counts(p->has_force ? p->force_n : 0.0);
    b->hal = (fw_hal){serial_write, p->sensor ? plate_sensor : NULL,
                      p->has_force ? force_sensor : NULL, NULL, NULL,
                      p->has_lateral ? force_pair : NULL};
    return &b->hal;
}

void host_board_step(host_board *b, const uint16_t *setpoint)
{
    for (unsigned ch = 0; ch < b->channels; ch++) {
        double u = setpoint[ch] * STEP_UM;
        b->plate_um[ch] = b->pole * b->plate_um[ch] + (1.0 - b->pole) * u;
    }
}
