/* The C receiver and encoder against the shared vectors (vectors/frames.json, written by
 * vectors/make_vectors.py from the Python codec). For each byte stream it prints the same
 * canonical text as make_vectors.render_stream and compares; for frames marked
 * "reencode" that the device side can send (Info, Status, Error), the C encoder must
 * reproduce the frame byte for byte. Exit 0 only if every vector agrees. */
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../core/rx.h"
#include "../core/tx.h"
#include "../core/wire.h"

static char text[1 << 20];
static size_t text_len;

static void out(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text + text_len, sizeof text - text_len, fmt, ap);
    va_end(ap);
    if (n > 0)
        text_len += (size_t)n < sizeof text - text_len ? (size_t)n : sizeof text - text_len - 1;
}

static void u16s(const uint8_t *le, size_t n)
{
    for (size_t i = 0; i < n; i++)
        out(i ? ",%u" : "%u", fw_le16(le + 2 * i));
}

/* Every second LE i16 of `pairs` from `first` on: one column of a ForceReport. */
static void i16s(const uint8_t *pairs, size_t count, unsigned first)
{
    for (size_t i = 0; i < count; i++)
        out(i ? ",%d" : "%d", (int16_t)fw_le16(pairs + 4 * i + 2 * first));
}

static void hex(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        out("%02x", p[i]);
}

static void render(const fw_msg *m)
{
    out("v%u seq=%u ", m->version, m->seq);
    switch (m->type) {
    case FW_HELLO:
        out("hello prefill=%" PRIu32, m->m.prefill);
        break;
    case FW_HEARTBEAT:
        out("heartbeat token=%" PRIu32, m->m.token);
        break;
    case FW_STOP:
        out("stop drain=%d", m->m.drain);
        break;
    case FW_MISSING:
        out("missing seqs=");
        u16s(m->m.missing.seqs, m->m.missing.count);
        break;
    case FW_RESEND:
        out("resend orig=%u ", m->orig_seq);
        /* fall through - the rest is the Block's */
    case FW_BLOCK: {
        const fw_block *b = &m->m.block;
        out("block start=%" PRIu64 " n=%u ch=%u amps=", b->start_index, b->n, b->channels);
        u16s(b->amps, (size_t)b->n * b->channels);
        out(" phases=");
        if (b->phases)
            u16s(b->phases, (size_t)b->n * b->channels);
        else
            out("-");
        break;
    }
    case FW_INFO: {
        const fw_info *i = &m->m.info;
        out("info version=%u channels=%u phases=%d sensor=%d force=%d rate_mhz=%" PRIu32
            " buffer=%" PRIu32 " watchdog_ms=%u ramp_ms=%u force_reports=%d limits=",
            i->version, i->channels, !!(i->flags & FW_FLAG_PHASES),
            !!(i->flags & FW_FLAG_SENSOR), !!(i->flags & FW_FLAG_FORCE), i->rate_mhz,
            i->buffer_samples, i->watchdog_ms, i->ramp_ms, !!(i->flags & FW_FLAG_FORCE_REPORTS));
        u16s(i->limits, i->channels);
        out(" name=");
        hex(i->name, i->name_len);
        break;
    }
    case FW_STATUS: {
        const fw_status *s = &m->m.status;
        out("status echo=%" PRIu32 " state=%u play=%" PRIu64 " level=%" PRIu32 " counters=",
            s->echo, s->state, s->play_index, s->level);
        for (int k = 0; k < FW_STATUS_COUNTERS; k++)
            out(k ? ",%" PRIu32 : "%" PRIu32, s->counters[k]);
        out(" measured=");
        if (s->n_measured)
            u16s(s->measured, s->n_measured);
        else
            out("-");
        if (s->has_force)
            out(" force_mn=%u", s->force_mn);
        else
            out(" force_mn=-");
        if (s->accounted)
            out(" accounting=%" PRIu64 ",%" PRIu32 ",%" PRIu32 ",%" PRIu32, s->buffer_end,
                s->played, s->flushed, s->flushes);
        else
            out(" accounting=-");
        break;
    }
    case FW_FLUSHED:
        out("flushed cause=%u play=%" PRIu64 " flushed=%" PRIu32 " flushes=%" PRIu32,
            m->m.flushed.cause, m->m.flushed.play_index, m->m.flushed.flushed,
            m->m.flushed.flushes);
        break;
    case FW_FORCE:
        out("force start=%" PRIu64 " decimation=%u lateral=", m->m.force.start_index,
            m->m.force.decimation);
        i16s(m->m.force.pairs, m->m.force.count, 0);
        out(" normal=");
        i16s(m->m.force.pairs, m->m.force.count, 1);
        break;
    case FW_ERROR:
        out("error code=%u ref=%u detail=%" PRIu32 " text=", m->m.error.code,
            m->m.error.ref_seq, m->m.error.detail);
        hex(m->m.error.text, m->m.error.text_len);
        break;
    }
}

/* ------------------------------------------------------------------ re-encoding */

static uint8_t encoded[8192];
static size_t encoded_len;

static void collect(void *ctx, const uint8_t *p, size_t n)
{
    (void)ctx;
    if (n > sizeof encoded - encoded_len)
        abort();
    memcpy(encoded + encoded_len, p, n);
    encoded_len += n;
}

/* Encode a decoded device-to-host message again, in its version; false for host-to-device
 * types (the device never sends them). */
static bool reencode(const fw_msg *m)
{
    static uint8_t body[FW_TX_OVERHEAD + FW_RX_CAPACITY];
    size_t n;
    switch (m->type) {
    case FW_INFO:
        n = fw_put_info(body + 4, &m->m.info);
        break;
    case FW_STATUS:
        n = fw_put_status(body + 4, &m->m.status);
        break;
    case FW_ERROR:
        n = fw_put_error(body + 4, &m->m.error);
        break;
    case FW_FLUSHED:
        n = fw_put_flushed(body + 4, &m->m.flushed);
        break;
    case FW_FORCE:
        n = fw_put_force(body + 4, &m->m.force);
        break;
    case FW_MISSING: {
        uint16_t seqs[FW_MISSING_MAX];
        for (uint8_t k = 0; k < m->m.missing.count; k++)
            seqs[k] = fw_le16(m->m.missing.seqs + 2 * k);
        n = fw_put_missing(body + 4, seqs, m->m.missing.count);
        break;
    }
    default:
        return false;
    }
    encoded_len = 0;
    fw_tx_frame(body, n, m->version, m->type, m->seq, collect, NULL);
    return true;
}

/* ------------------------------------------------------------------ one vector */

static const char *drop_names[] = {"crc", "cobs", "short", "oversize", "version", "type",
                                   "payload"};

static void drop_counts(const fw_rx_counts *c, uint32_t v[7])
{
    uint32_t now[7] = {c->crc_errors, c->cobs_errors, c->short_frames, c->oversize,
                       c->bad_version, c->unknown_type, c->bad_payload};
    memcpy(v, now, sizeof now);
}

static fw_rx rx;
static uint8_t stream[1 << 16];

/* Returns 0 if the vector agrees, 1 if not (and says why). */
static int check(const char *name, const char *hexs, const char *expect, bool reenc,
                 unsigned *reencoded)
{
    size_t n = strlen(hexs) / 2;
    if (n > sizeof stream) {
        fprintf(stderr, "%s: stream too long\n", name);
        return 1;
    }
    for (size_t i = 0; i < n; i++) {
        unsigned v;
        sscanf(hexs + 2 * i, "%2x", &v);
        stream[i] = (uint8_t)v;
    }
    fw_rx_init(&rx, FW_NEWEST_VERSION);
    text_len = 0;
    text[0] = '\0';
    uint32_t before[7], after[7];
    drop_counts(&rx.counts, before);
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        fw_msg m;
        if (fw_rx_byte(&rx, stream[i], &m)) {
            render(&m);
            out(" | ");
            if (reenc && reencode(&m)) {
                (*reencoded)++;
                if (encoded_len != n || memcmp(encoded, stream, n)) {
                    fprintf(stderr, "%s: the C encoder wrote a different frame\n", name);
                    bad = 1;
                }
            }
        }
        drop_counts(&rx.counts, after);
        /* the Python renderer lists drops in its counter order */
        static const int order[7] = {1, 2, 0, 4, 5, 6, 3};
        for (int k = 0; k < 7; k++)
            for (uint32_t d = before[order[k]]; d < after[order[k]]; d++)
                out("drop %s | ", drop_names[order[k]]);
        memcpy(before, after, sizeof after);
    }
    out("counts ok=%" PRIu32 " lost=%" PRIu32 " discarded=%" PRIu32, rx.counts.frames_ok,
        rx.counts.lost_frames, fw_rx_discarded(&rx.counts));
    if (strcmp(text, expect)) {
        size_t k = 0;
        while (text[k] && text[k] == expect[k])
            k++;
        fprintf(stderr, "%s: decodes differ at character %zu\n  C:      %.160s\n  Python: %.160s\n",
                name, k, text + (k > 40 ? k - 40 : 0), expect + (k > 40 ? k - 40 : 0));
        bad = 1;
    }
    return bad;
}

/* The generated file has one vector per line; pull a string field out of a line. */
static char *field(char *line, const char *key)
{
    char pattern[32];
    snprintf(pattern, sizeof pattern, "\"%s\": \"", key);
    char *start = strstr(line, pattern);
    if (!start)
        return NULL;
    start += strlen(pattern);
    char *end = strchr(start, '"');
    if (!end)
        return NULL;
    *end = '\0';
    return start;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: check_vectors vectors/frames.json\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "r");
    if (!f) {
        perror(argv[1]);
        return 2;
    }
    char *line = NULL;
    size_t cap = 0;
    unsigned total = 0, failed = 0, reencoded = 0;
    while (getline(&line, &cap, f) > 0) {
        bool reenc = strstr(line, "\"reencode\": true") != NULL;
        char *expect = strstr(line, "\"expect\": \"");
        char *hexs = strstr(line, "\"hex\": \"");
        if (!expect || !hexs)
            continue;
        char *e = field(expect, "expect"), *h = field(hexs, "hex"), *name = field(line, "name");
        total++;
        failed += (unsigned)check(name ? name : "?", h, e, reenc, &reencoded);
    }
    free(line);
    fclose(f);
    printf("%u vectors, %u failed; %u frames re-encoded by the C encoder\n", total, failed,
           reencoded);
    return failed || total == 0 ? 1 : 0;
}
