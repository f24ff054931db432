#include "tx.h"

#include "crc32.h"
#include "wire.h"

/* Same block boundaries as the reference encoder: a run of 254 non-zero bytes is a 0xFF
 * block, and every zero-separated piece (even an empty last one) ends in a short block. */
static void cobs(const uint8_t *p, size_t n, fw_sink sink, void *ctx)
{
    static const uint8_t full = 0xFF, delimiter = 0x00;
    size_t i = 0;
    for (;;) {
        size_t end = i;
        while (end < n && p[end] != 0)
            end++;
        for (; end - i >= 254; i += 254) {
            sink(ctx, &full, 1);
            sink(ctx, p + i, 254);
        }
        uint8_t code = (uint8_t)(end - i + 1);
        sink(ctx, &code, 1);
        sink(ctx, p + i, end - i);
        if (end == n)
            break;
        i = end + 1;
    }
    sink(ctx, &delimiter, 1);
}

void fw_tx_frame(uint8_t *body, size_t payload_len, uint8_t version, uint8_t type,
                 uint16_t seq, fw_sink sink, void *ctx)
{
    body[0] = version;
    body[1] = type;
    fw_put16(body + 2, seq);
    size_t n = 4 + payload_len;
    fw_put32(body + n, fw_crc32(body, n));
    cobs(body, n + 4, sink, ctx);
}
