#include "wire.h"

#include <string.h>

#include "utf8.h"

#define INFO_HEAD 16u   /* version channels flags rate buffer watchdog ramp name_len */
#define BLOCK_HEAD 12u  /* start_index n channels flags */
#define STATUS_HEAD 58u /* echo state flags play_index level 9 counters n_measured */
#define STATUS_V2 20u  /* buffer_end played flushed flushes, after n_measured */
#define ERROR_HEAD 7u   /* code ref_seq detail */
#define FLUSHED_LEN 17u /* cause play_index flushed flushes */
#define FORCE_HEAD 11u  /* start_index decimation count, then count x (i16, i16) */

uint32_t fw_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

uint64_t fw_le64(const uint8_t *p) { return fw_le32(p) | ((uint64_t)fw_le32(p + 4) << 32); }

uint8_t *fw_put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    return p + 2;
}

uint8_t *fw_put32(uint8_t *p, uint32_t v)
{
    return fw_put16(fw_put16(p, (uint16_t)v), (uint16_t)(v >> 16));
}

uint8_t *fw_put64(uint8_t *p, uint64_t v)
{
    return fw_put32(fw_put32(p, (uint32_t)v), (uint32_t)(v >> 32));
}

static bool parse_block(const uint8_t *p, size_t n, fw_block *b)
{
    if (n < BLOCK_HEAD)
        return false;
    b->start_index = fw_le64(p);
    b->n = fw_le16(p + 8);
    b->channels = p[10];
    b->flags = p[11];
    size_t words = (size_t)b->n * b->channels * ((b->flags & FW_FLAG_PHASES) ? 2u : 1u);
    if (b->channels < 1 || n - BLOCK_HEAD != 2u * words)
        return false;
    b->amps = p + BLOCK_HEAD;
    b->phases = (b->flags & FW_FLAG_PHASES) ? b->amps + 2u * b->n * b->channels : NULL;
    return true;
}

static bool parse_info(const uint8_t *p, size_t n, fw_info *m)
{
    if (n < INFO_HEAD)
        return false;
    m->version = p[0];
    m->channels = p[1];
    m->flags = p[2];
    m->rate_mhz = fw_le32(p + 3);
    m->buffer_samples = fw_le32(p + 7);
    m->watchdog_ms = fw_le16(p + 11);
    m->ramp_ms = fw_le16(p + 13);
    m->name_len = p[15];
    m->limits = p + INFO_HEAD;
    m->name = m->limits + 2u * m->channels;
    return m->channels >= 1 && n - INFO_HEAD == 2u * m->channels + m->name_len &&
           fw_utf8_valid(m->name, m->name_len);
}

static bool parse_status(uint8_t version, const uint8_t *p, size_t n, fw_status *m)
{
    m->accounted = version >= 2;
    size_t head = STATUS_HEAD + (m->accounted ? STATUS_V2 : 0u);
    if (n < head)
        return false;
    m->echo = fw_le32(p);
    m->state = p[4];
    uint8_t flags = p[5];
    m->play_index = fw_le64(p + 6);
    m->level = fw_le32(p + 14);
    for (int i = 0; i < FW_STATUS_COUNTERS; i++)
        m->counters[i] = fw_le32(p + 18 + 4 * i);
    m->n_measured = fw_le32(p + 54);
    if (m->accounted) {
        m->buffer_end = fw_le64(p + STATUS_HEAD);
        m->played = fw_le32(p + STATUS_HEAD + 8);
        m->flushed = fw_le32(p + STATUS_HEAD + 12);
        m->flushes = fw_le32(p + STATUS_HEAD + 16);
    }
    m->measured = p + head;
    m->has_force = (flags & FW_FLAG_FORCE) != 0;
    uint64_t rest = 2u * (uint64_t)m->n_measured + (m->has_force ? 2u : 0u);
    if (rest != n - head || ((flags & FW_FLAG_SENSOR) != 0) != (m->n_measured > 0))
        return false;
    m->force_mn = m->has_force ? fw_le16(p + n - 2) : 0;
    return true;
}

static bool parse_error(const uint8_t *p, size_t n, fw_error *m)
{
    if (n < ERROR_HEAD)
        return false;
    m->code = p[0];
    m->ref_seq = fw_le16(p + 1);
    m->detail = fw_le32(p + 3);
    m->text = p + ERROR_HEAD;
    m->text_len = n - ERROR_HEAD;
    return fw_utf8_valid(m->text, m->text_len);
}

static bool parse_flushed(const uint8_t *p, size_t n, fw_flushed *m)
{
    if (n != FLUSHED_LEN)
        return false;
    m->cause = p[0];
    m->play_index = fw_le64(p + 1);
    m->flushed = fw_le32(p + 9);
    m->flushes = fw_le32(p + 13);
    return true;
}

static bool parse_force(const uint8_t *p, size_t n, fw_force *m)
{
    if (n < FORCE_HEAD)
        return false;
    m->start_index = fw_le64(p);
    m->decimation = fw_le16(p + 8);
    m->count = p[10];
    m->pairs = p + FORCE_HEAD;
    return m->count >= 1 && m->decimation >= 1 && n - FORCE_HEAD == 4u * m->count;
}

bool fw_known_type(uint8_t version, uint8_t type)
{
    return (type >= FW_HELLO && type <= FW_STOP) || (type >= FW_INFO && type <= FW_ERROR) ||
           (type == FW_FLUSHED && version >= 2) || (type == FW_FORCE && version >= 3) ||
           ((type == FW_RESEND || type == FW_MISSING) && version >= 4);
}

bool fw_parse(uint8_t version, uint8_t type, const uint8_t *p, size_t n, fw_msg *out)
{
    out->type = type;
    out->version = version;
    switch (type) {
    case FW_HELLO:
        out->m.prefill = n == 4 ? fw_le32(p) : 0;
        return n == 4;
    case FW_HEARTBEAT:
        out->m.token = n == 4 ? fw_le32(p) : 0;
        return n == 4;
    case FW_STOP:
        out->m.drain = n == 1 && p[0] == 1;
        return n == 1 && p[0] <= 1; /* 4.5 defines 0 and 1 only */
    case FW_BLOCK:
        return parse_block(p, n, &out->m.block);
    case FW_RESEND:
        if (n < 2)
            return false;
        out->orig_seq = fw_le16(p);
        return parse_block(p + 2, n - 2, &out->m.block);
    case FW_MISSING:
        out->m.missing.count = n ? p[0] : 0;
        out->m.missing.seqs = p + 1;
        return n >= 1 && p[0] >= 1 && p[0] <= FW_MISSING_MAX && n == 1u + 2u * p[0];
    case FW_INFO:
        return parse_info(p, n, &out->m.info);
    case FW_STATUS:
        return parse_status(version, p, n, &out->m.status);
    case FW_ERROR:
        return parse_error(p, n, &out->m.error);
    case FW_FLUSHED:
        return parse_flushed(p, n, &out->m.flushed);
    case FW_FORCE:
        return parse_force(p, n, &out->m.force);
    default:
        return false;
    }
}

size_t fw_put_info(uint8_t *out, const fw_info *m)
{
    uint8_t *p = out;
    *p++ = m->version;
    *p++ = m->channels;
    *p++ = m->flags;
    p = fw_put32(p, m->rate_mhz);
    p = fw_put32(p, m->buffer_samples);
    p = fw_put16(p, m->watchdog_ms);
    p = fw_put16(p, m->ramp_ms);
    *p++ = m->name_len;
    memcpy(p, m->limits, 2u * m->channels);
    p += 2u * m->channels;
    memcpy(p, m->name, m->name_len);
    return (size_t)(p - out) + m->name_len;
}

size_t fw_put_status(uint8_t *out, const fw_status *m)
{
    uint8_t *p = fw_put32(out, m->echo);
    *p++ = m->state;
    *p++ = (uint8_t)((m->n_measured ? FW_FLAG_SENSOR : 0u) | (m->has_force ? FW_FLAG_FORCE : 0u));
    p = fw_put64(p, m->play_index);
    p = fw_put32(p, m->level);
    for (int i = 0; i < FW_STATUS_COUNTERS; i++)
        p = fw_put32(p, m->counters[i]);
    p = fw_put32(p, m->n_measured);
    if (m->accounted) {
        p = fw_put64(p, m->buffer_end);
        p = fw_put32(p, m->played);
        p = fw_put32(p, m->flushed);
        p = fw_put32(p, m->flushes);
    }
    memcpy(p, m->measured, 2u * m->n_measured);
    p += 2u * m->n_measured;
    if (m->has_force)
        p = fw_put16(p, m->force_mn);
    return (size_t)(p - out);
}

size_t fw_put_error(uint8_t *out, const fw_error *m)
{
    size_t len = m->text_len < FW_ERROR_TEXT_MAX ? m->text_len : FW_ERROR_TEXT_MAX;
    uint8_t *p = out;
    *p++ = m->code;
    p = fw_put16(p, m->ref_seq);
    p = fw_put32(p, m->detail);
    memmove(p, m->text, len); /* the text may already be in place */
    return ERROR_HEAD + len;
}

size_t fw_put_flushed(uint8_t *out, const fw_flushed *m)
{
    out[0] = m->cause;
    fw_put32(fw_put32(fw_put64(out + 1, m->play_index), m->flushed), m->flushes);
    return FLUSHED_LEN;
}

size_t fw_put_force(uint8_t *out, const fw_force *m)
{
    uint8_t *p = fw_put16(fw_put64(out, m->start_index), m->decimation);
    *p++ = m->count;
    memmove(p, m->pairs, 4u * m->count); /* the values may already be in place */
    return FORCE_HEAD + 4u * m->count;
}

size_t fw_put_missing(uint8_t *out, const uint16_t *seqs, uint8_t count)
{
    uint8_t *p = out;
    *p++ = count;
    for (uint8_t k = 0; k < count; k++)
        p = fw_put16(p, seqs[k]);
    return (size_t)(p - out);
}
