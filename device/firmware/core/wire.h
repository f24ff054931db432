/* Messages of PROTOCOL.md 4 and their payload layouts (little-endian, section 2).
 * Variable-length parts are views into the frame's bytes (u16 arrays stay
 * little-endian; read them with fw_le16). */
#ifndef FW_WIRE_H
#define FW_WIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Versions 1 to FW_NEWEST_VERSION are spoken (PROTOCOL.md 2.1). */
#define FW_NEWEST_VERSION 4u

enum fw_type {
    FW_HELLO = 0x01, FW_BLOCK = 0x02, FW_HEARTBEAT = 0x03, FW_STOP = 0x04,
    FW_INFO = 0x81, FW_STATUS = 0x82, FW_ERROR = 0x83, FW_FLUSHED = 0x84, /* version 2 */
    FW_FORCE = 0x85, /* version 3 */
    FW_RESEND = 0x05, FW_MISSING = 0x86, /* version 4 */
};

/* Types from here up travel device -> host; below, host -> device (PROTOCOL.md 4). */
#define FW_DEVICE_TYPES 0x80u

enum fw_state { FW_IDLE, FW_BUFFERING, FW_PLAYING, FW_DRAINING, FW_SILENT };

enum fw_error_code {
    FW_BAD_VERSION = 1, FW_NOT_READY = 2, FW_BAD_BLOCK = 3, FW_OVERFLOW = 4, FW_LATE = 5,
};

#define FW_FLUSH_WATCHDOG 1u /* Flushed.cause */

/* Info.flags and Block.flags / Status.flags bits. */
#define FW_FLAG_PHASES 0x01u
#define FW_FLAG_SENSOR 0x02u
#define FW_FLAG_FORCE 0x04u
#define FW_FLAG_FORCE_REPORTS 0x08u /* Info only: the device sends ForceReports (4.9) */

#define FW_ERROR_TEXT_MAX 200u
#define FW_STATUS_COUNTERS 9

typedef struct {
    uint64_t start_index;
    uint16_t n;
    uint8_t channels;
    uint8_t flags;
    const uint8_t *amps;   /* n * channels LE u16, sample-major */
    const uint8_t *phases; /* same, or NULL */
} fw_block;

typedef struct {
    uint8_t version, channels, flags;
    uint32_t rate_mhz, buffer_samples;
    uint16_t watchdog_ms, ramp_ms;
    const uint8_t *limits; /* channels LE u16 */
    const uint8_t *name;
    uint8_t name_len;
} fw_info;

/* counters, in wire order: underruns, crc_errors, frames_ok, lost_frames, gap_samples,
 * late_samples, overflow_samples, watchdog_trips, clamped (PROTOCOL.md 4.6). */
typedef struct {
    uint32_t echo;
    uint8_t state;
    uint64_t play_index;
    uint32_t level;
    uint32_t counters[FW_STATUS_COUNTERS];
    uint32_t n_measured;
    const uint8_t *measured; /* n_measured LE u16 */
    bool has_force;
    uint16_t force_mn;
    bool accounted; /* the version 2 fields below are on the wire */
    uint64_t buffer_end;
    uint32_t played, flushed, flushes; /* since the last Hello */
} fw_status;

typedef struct {
    uint8_t cause;
    uint64_t play_index;
    uint32_t flushed, flushes;
} fw_flushed;

/* ForceReport (PROTOCOL.md 4.9): count values of decimation samples from start_index;
 * pairs: count x (lateral, normal) LE i16, counts of 1/4096 N. */
typedef struct {
    uint64_t start_index;
    uint16_t decimation;
    uint8_t count;
    const uint8_t *pairs;
} fw_force;

typedef struct {
    uint8_t code;
    uint16_t ref_seq;
    uint32_t detail;
    const uint8_t *text;
    size_t text_len;
} fw_error;

/* Missing (version 4): count sequence numbers, LE u16 each (PROTOCOL.md 4.10). */
#define FW_MISSING_MAX 16u
typedef struct {
    uint8_t count;
    const uint8_t *seqs;
} fw_missing;

typedef struct {
    uint16_t seq;
    uint16_t lost;     /* frames missing just before this one (its seq skipped ahead) */
    uint16_t orig_seq; /* Resend: the seq of the frame that first carried m.block */
    uint8_t version;
    uint8_t type;
    union {
        uint32_t prefill; /* Hello */
        uint32_t token;   /* Heartbeat */
        bool drain;       /* Stop */
        fw_block block;
        fw_info info;
        fw_status status;
        fw_error error;
        fw_flushed flushed;
        fw_force force;
        fw_missing missing;
    } m;
} fw_msg;

static inline uint16_t fw_le16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
uint32_t fw_le32(const uint8_t *p);
uint64_t fw_le64(const uint8_t *p);
uint8_t *fw_put16(uint8_t *p, uint16_t v);
uint8_t *fw_put32(uint8_t *p, uint32_t v);
uint8_t *fw_put64(uint8_t *p, uint64_t v);

/* Whether `type` exists in protocol `version` (Flushed from version 2, ForceReport 3,
 * Resend and Missing 4). */
bool fw_known_type(uint8_t version, uint8_t type);

/* Parse the payload of a known message of `type` in a `version` frame; false if the
 * payload does not fit it (PROTOCOL.md 2: "the payload length does not match its type"). */
bool fw_parse(uint8_t version, uint8_t type, const uint8_t *p, size_t n, fw_msg *out);

/* Payload writers for what a device sends; each returns the bytes written. Worst case:
 * Info 16 + 2 * channels + name_len, Status 80 + 2 * n_measured, Error 7 + 200,
 * Flushed 17, ForceReport 11 + 4 * count, Missing 1 + 2 * count. */
size_t fw_put_info(uint8_t *out, const fw_info *m);
size_t fw_put_status(uint8_t *out, const fw_status *m);
size_t fw_put_error(uint8_t *out, const fw_error *m);
size_t fw_put_flushed(uint8_t *out, const fw_flushed *m);
size_t fw_put_force(uint8_t *out, const fw_force *m);
size_t fw_put_missing(uint8_t *out, const uint16_t *seqs, uint8_t count);

#endif
