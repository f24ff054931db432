/* Sending side of PROTOCOL.md 2: header, CRC, COBS and the delimiter, streamed to a sink
 * (no second buffer for the stuffed bytes). */
#ifndef FW_TX_H
#define FW_TX_H

#include <stddef.h>
#include <stdint.h>

typedef void (*fw_sink)(void *ctx, const uint8_t *p, size_t n);

/* Bytes of a body around a payload: version type seq before, crc after. */
#define FW_TX_OVERHEAD 8u

/* body: room for FW_TX_OVERHEAD + payload_len bytes, the payload already at body + 4. */
void fw_tx_frame(uint8_t *body, size_t payload_len, uint8_t version, uint8_t type,
                 uint16_t seq, fw_sink sink, void *ctx);

#endif
