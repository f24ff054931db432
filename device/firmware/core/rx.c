#include "rx.h"

#include "crc32.h"

static void restart(fw_rx *rx)
{
    rx->len = rx->stuffed = 0;
    rx->code = rx->left = 0;
    rx->zero_pending = rx->overflowed = false;
    rx->crc = FW_CRC32_INIT;
}

void fw_rx_init(fw_rx *rx, uint8_t max_version)
{
    *rx = (fw_rx){0};
    rx->max_version = max_version;
    restart(rx);
}

uint32_t fw_rx_discarded(const fw_rx_counts *c)
{
    return c->crc_errors + c->cobs_errors + c->short_frames + c->oversize + c->bad_version +
           c->unknown_type + c->bad_payload;
}

static void put(fw_rx *rx, uint8_t b)
{
    rx->body[rx->len++] = b;
    if (rx->len >= 5) /* body[len - 5] can no longer be part of the trailing CRC */
        rx->crc = fw_crc32_byte(rx->crc, rx->body[rx->len - 5]);
}

/* Follow the host's sequence numbers through a host -> device frame of type `type` and
 * number `seq`; returns how many frames were skipped just before it. Only host frames
 * count: a device -> host frame reaching this receiver is the device's own echoed back
 * (PROTOCOL.md 5.3), numbered by the device, and would fake or hide a loss. */
static uint16_t count_seq(fw_rx *rx, uint8_t type, uint16_t seq)
{
    if (type == FW_HELLO)
        rx->seq_known = false; /* a new host numbers from anywhere (PROTOCOL.md 2) */
    uint16_t skipped = (uint16_t)(seq - rx->next_seq);
    if (!rx->seq_known || skipped >= 0x8000u) /* a jump backwards is a restart, not a loss */
        skipped = 0;
    rx->counts.lost_frames += skipped;
    rx->next_seq = (uint16_t)(seq + 1u);
    rx->seq_known = true;
    return skipped;
}

static bool check(fw_rx *rx, fw_msg *msg)
{
    fw_rx_counts *c = &rx->counts;
    if (rx->overflowed) {
        c->oversize++;
        return false;
    }
    if (rx->stuffed == 0)
        return false; /* an empty frame is ignored, not counted */
    if (rx->left) {
        c->cobs_errors++; /* the last COBS block ends past the delimiter */
        return false;
    }
    if (rx->len > FW_MAX_BODY) { /* zeros stuff cheaply: 4113 bytes decode to up to 4112 */
        c->oversize++;
        return false;
    }
    if (rx->len < 8) {
        c->short_frames++;
        return false;
    }
    if (~rx->crc != fw_le32(rx->body + rx->len - 4)) {
        c->crc_errors++;
        return false;
    }
    uint8_t version = rx->body[0], type = rx->body[1];
    if (version < 1 || version > rx->max_version) {
        c->bad_version++;
        return false;
    }
    if (!fw_known_type(version, type)) {
        c->unknown_type++;
        return false;
    }
    if (!fw_parse(version, type, rx->body + 4, rx->len - 8u, msg)) {
        c->bad_payload++;
        return false;
    }
    msg->seq = fw_le16(rx->body + 2);
    msg->lost = type < FW_DEVICE_TYPES ? count_seq(rx, type, msg->seq) : 0;
    c->frames_ok++;
    return true;
}

bool fw_rx_byte(fw_rx *rx, uint8_t b, fw_msg *msg)
{
    if (b == 0) {
        bool ok = check(rx, msg);
        restart(rx);
        return ok;
    }
    if (rx->overflowed)
        return false;
    if (++rx->stuffed > FW_MAX_STUFFED) {
        rx->overflowed = true; /* discard up to the next delimiter */
        return false;
    }
    if (rx->left == 0) { /* a code byte: the previous block, if short, ended in a zero */
        if (rx->zero_pending)
            put(rx, 0);
        rx->code = b;
        rx->left = (uint8_t)(b - 1u);
    } else {
        put(rx, b);
        rx->left--;
    }
    rx->zero_pending = rx->left == 0 && rx->code < 255u;
    return false;
}
