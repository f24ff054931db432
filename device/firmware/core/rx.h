/* Receiving side of PROTOCOL.md 2: bytes in, whole checked messages out.
 *
 * COBS is undone as bytes arrive and the CRC is accumulated on the fly, so a frame
 * costs no burst of work at its delimiter. A frame is delivered only if it passed every
 * check; anything else is counted by reason and has no other effect.
 *
 * This is the device's receiver: lost_frames and fw_msg.lost follow the host's sequence
 * numbers only. A frame of a device -> host type (the device's own, echoed back) is
 * delivered and counted in frames_ok, with lost 0, and leaves that bookkeeping alone. */
#ifndef FW_RX_H
#define FW_RX_H

#include <stdbool.h>
#include <stdint.h>

#include "fw_limits.h"
#include "wire.h"

typedef struct {
    uint32_t frames_ok, crc_errors, cobs_errors, short_frames, oversize, bad_version,
        unknown_type, bad_payload, lost_frames;
} fw_rx_counts;

typedef struct {
    uint8_t body[FW_RX_CAPACITY];
    uint16_t len;     /* decoded bytes so far */
    uint16_t stuffed; /* stuffed bytes so far */
    uint8_t code;     /* code byte of the COBS block being read */
    uint8_t left;     /* data bytes still to come in that block */
    bool zero_pending, overflowed, seq_known;
    uint8_t max_version; /* newest version accepted (PROTOCOL.md 2.1) */
    uint16_t next_seq;
    uint32_t crc; /* running CRC of body[0 .. len - 4) */
    fw_rx_counts counts;
} fw_rx;

void fw_rx_init(fw_rx *rx, uint8_t max_version);

/* Feed one byte. Returns true when it completes a frame that passed every check of
 * PROTOCOL.md 2; *msg then holds it, its views valid until the next call. */
bool fw_rx_byte(fw_rx *rx, uint8_t b, fw_msg *msg);

/* Frames dropped for any reason (the Status crc_errors counter). */
uint32_t fw_rx_discarded(const fw_rx_counts *c);

#endif
