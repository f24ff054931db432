/* The host port's "board": replies collected in memory, the plate's amplitude loop
 * modelled as in PROTOCOL.md 5.4 (its output is the amplitude sensor), a constant normal
 * force sensor and a lateral force sensor (constant, or per tick from a table the
 * virtual-clock library is given). Shared by the pty process and that library. */
#ifndef HOST_BOARD_H
#define HOST_BOARD_H

#include <stddef.h>
#include <stdint.h>

#include "../core/device.h"
#include "params.h"

typedef struct {
    double pole;                  /* exp(-2 pi f_c / f_s): y = pole y + (1 - pole) u */
    double plate_um[FW_MAX_CHANNELS];
    unsigned channels;
    uint16_t force_mn;
    int16_t forces[2];           /* lateral, normal (counts of 1/4096 N) ... */
    const int16_t *forces_now;   /* ... or these, when not NULL */
    fw_hal hal;
    uint8_t *tx; /* replies of the frame being handled */
    size_t tx_len, tx_cap;
} host_board;

/* The fw_hal for a board with or without each sensor. */
const fw_hal *host_board_init(host_board *b, const host_params *p);

/* Advance the plate model by one tick of setpoints (counts). */
void host_board_step(host_board *b, const uint16_t *setpoint);

#endif
